"""The ROS 1 environment `usar-arm ros --ros1 --setup` makes: Debian's interpreter with ROS 1's
packages first and this interpreter's after, control_msgs generated with Noetic's MD5 sums, a
second setup that finds the first, and the one-line errors (no ROS 1, no roscore)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.ros1.helpers import ROOT, free_port
from usar_arm.ros import ros1_setup

NOETIC_MD5 = {
    # control_msgs 1.5 (Noetic) as its generated code in public ROS 1 client libraries
    # (rosserial's headers, roslisp's and C# ports) states them.
    "FollowJointTrajectoryGoal": "69636787b6ecbde4d61d711979bc7ecb",
    "FollowJointTrajectoryActionGoal": "cff5c1d533bf2f82dd0138d57f4304bb",
    "FollowJointTrajectoryResult": "493383b18409bfb604b4e26c676401d2",
    "FollowJointTrajectoryActionResult": "c4fb3b000dc9da4fd99699380efcc5d9",
    "FollowJointTrajectoryFeedback": "10817c60c2486ef6b33e97dcd87f4474",
    "FollowJointTrajectoryActionFeedback": "d8920dc4eae9fc107e00999cce4be641",
}


def _ros1(env: ros1_setup.Ros1Environment, code: str) -> str:
    done = subprocess.run([str(env.python), "-c", code], capture_output=True, text=True,
                          timeout=120, env=env.environ(), check=False, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def test_the_generated_control_msgs_are_noetics_on_the_wire(
        ros1_env: ros1_setup.Ros1Environment) -> None:
    out = _ros1(ros1_env, "import json, control_msgs.msg as c\n"
                          f"print(json.dumps({{n: getattr(c, n)._md5sum for n in "
                          f"{list(NOETIC_MD5)!r}}}))")
    assert json.loads(out) == NOETIC_MD5


def test_ros1_packages_come_first_and_this_interpreters_after(
        ros1_env: ros1_setup.Ros1Environment) -> None:
    out = json.loads(_ros1(ros1_env, (
        "import json, sys, std_msgs, sensor_msgs, rospy, numpy, yaml, usar_arm, pinocchio\n"
        "print(json.dumps({'std_msgs': std_msgs.__file__, 'sensor_msgs': sensor_msgs.__file__,"
        " 'rospy': rospy.__file__, 'numpy': numpy.__version__, 'yaml': yaml.__file__, "
        "'usar_arm': usar_arm.__file__, 'python': sys.version}))")))
    for name in ("std_msgs", "sensor_msgs", "rospy"):  # Debian's ROS 1, not ROS 2's wheels
        assert Path(out[name]).resolve().is_relative_to(ros1_setup.DIST_PACKAGES), out[name]
    import numpy
    import yaml

    import usar_arm
    assert out["numpy"] == numpy.__version__  # this interpreter's, not Debian's
    assert Path(out["yaml"]).resolve() == Path(yaml.__file__).resolve()
    assert Path(out["usar_arm"]).resolve() == Path(usar_arm.__file__).resolve()
    debian = subprocess.run([str(ros1_setup.SYSTEM_PYTHON), "-c", "import sys; "
                             "print(sys.version)"], capture_output=True, text=True, check=True)
    assert out["python"] == debian.stdout.strip(), "Debian's interpreter runs ROS 1"


def test_a_second_setup_finds_the_first_at_once(ros1_env: ros1_setup.Ros1Environment) -> None:
    started = time.perf_counter()
    again = ros1_setup.setup()
    took = time.perf_counter() - started
    assert again.root == ros1_env.root
    assert took < 2.0, f"the second setup took {took:.2f} s"


def test_missing_debian_packages_are_one_line_with_the_apt_command() -> None:
    needs = (("/nonexistent/rospy", "python3-rospy"), ("/usr/bin/python3", "python3"))
    with pytest.raises(ros1_setup.Ros1SetupError) as caught:
        ros1_setup.require_debian(needs)
    message = str(caught.value)
    assert "\n" not in message
    assert "missing python3-rospy" in message
    assert "apt-get install -y --no-install-recommends python3 python3-rospy" in message
    assert caught.value.exit_code == 69


def test_without_a_roscore_the_node_says_so_in_one_line(tmp_path: Path) -> None:
    uri = f"http://127.0.0.1:{free_port()}"
    done = subprocess.run([sys.executable, "-m", "usar_arm", "ros", "--ros1"],
                          capture_output=True, text=True, timeout=120, cwd=ROOT, check=False,
                          env={**os.environ, "ROS_MASTER_URI": uri,
                               "ROS_HOME": str(tmp_path)})
    assert done.returncode == 69, done.stderr[-2000:]
    errors = [line for line in done.stderr.splitlines() if "error" in line]
    assert len(errors) == 1, done.stderr[-2000:]
    assert "roscore" in errors[0] and "ROS_MASTER_URI" in errors[0] and uri in errors[0]
