"""The two message packages usar-arm builds: their type hashes are ROS 2 Jazzy's, and a
missing extra, build or compiler is a one-line error naming the fix."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed: pip install "
                                    "'usar-arm[ros]'")

from usar_arm.ros.build import built, cache_key

# The RIHS01 hashes a ROS 2 Jazzy system advertises for these types (control_msgs 5.x).
JAZZY = {
    "tf2_msgs/msg/TFMessage":
        "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
    "tf2_msgs/msg/TF2Error":
        "RIHS01_db2485e7d6a0ec75bf087e058ee45df682acc3a621ca7780503d10aac141809a",
    "control_msgs/action/FollowJointTrajectory":
        "RIHS01_738ebcb7a2d7cfa42f9f1001cc99ce3a4383d1cfe508015d9be8485e4b1c66f6",
    "control_msgs/action/FollowJointTrajectory_Goal":
        "RIHS01_8a9060704b269608f5a340934cc26e66869dd14bdac29e2e7fd9ec8b9882d205",
    "control_msgs/action/FollowJointTrajectory_Result":
        "RIHS01_8002e99ed2c14c6faa522f2a93c26d744c5982f254f9e98ff9c6f19789bdb220",
    "control_msgs/action/FollowJointTrajectory_Feedback":
        "RIHS01_3fd0aaecf71725121ae1ff7f01098a5e0da581e672be18a6b2c286cb43d96b49",
}
ROOT = Path(__file__).resolve().parents[2]


def _built_hashes() -> dict[str, str]:
    entry = built()
    assert entry is not None
    hashes: dict[str, str] = {}
    for path in (entry.root / "install" / "share").glob("*/*/*.json"):
        for item in json.loads(path.read_text())["type_hashes"]:
            hashes[item["type_name"]] = item["hash_string"]
    return hashes


def test_the_built_types_hash_as_ros2_jazzy_advertises_them() -> None:
    hashes = _built_hashes()
    assert {name: hashes.get(name) for name in JAZZY} == JAZZY


def test_the_cache_key_changes_with_the_definitions(tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    from usar_arm.ros import build

    before = cache_key()
    copy = tmp_path / "interfaces"
    import shutil

    shutil.copytree(build.INTERFACES, copy)
    monkeypatch.setattr(build, "INTERFACES", copy)
    assert cache_key() == before
    (copy / "tf2_msgs" / "msg" / "TFMessage.msg").write_text("string transforms\n")
    assert cache_key() != before


def _usar_arm(args: list[str], **env: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "usar_arm", *args], capture_output=True,
                          text=True, timeout=120, check=False, cwd=ROOT,
                          env={**os.environ, **env})


def test_without_the_message_build_the_node_says_which_command_fixes_it(tmp_path: Path
                                                                         ) -> None:
    done = _usar_arm(["ros"], USAR_ARM_ROS_CACHE=str(tmp_path / "empty"))
    assert done.returncode == 69, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "usar-arm ros --setup" in lines[0], done.stderr


def test_without_a_compiler_the_build_says_so_in_one_line(tmp_path: Path) -> None:
    scripts = Path(sys.executable).parent  # python and cmake, no compiler
    env = {k: v for k, v in os.environ.items() if k not in ("CXX", "CC")}
    done = subprocess.run([sys.executable, "-m", "usar_arm", "ros", "--setup"],
                          capture_output=True, text=True, timeout=120, check=False, cwd=ROOT,
                          env={**env, "PATH": str(scripts),
                               "USAR_ARM_ROS_CACHE": str(tmp_path / "fresh")})
    assert done.returncode == 69, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "no C/C++ compiler" in lines[0], done.stderr


def test_the_built_packages_load_in_a_fresh_process() -> None:
    code = ("from usar_arm.ros.build import ensure_importable; ensure_importable()\n"
            "import rclpy\nfrom tf2_msgs.msg import TFMessage\n"
            "from control_msgs.action import FollowJointTrajectory\n"
            "rclpy.init(domain_id=101)\nn = rclpy.create_node('probe')\n"
            "n.create_publisher(TFMessage, 'tf', 1)\n"
            "print(n.get_publishers_info_by_topic('/tf')[0].topic_type_hash)\n"
            "rclpy.shutdown()\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=False, cwd=ROOT,
                          env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == JAZZY["tf2_msgs/msg/TFMessage"]


def test_without_the_ros_extra_the_node_says_how_to_install_it() -> None:
    code = ("import sys\nsys.modules['rclpy'] = None  # as if the extra were not installed\n"
            "from usar_arm.cli.main import main\nsys.exit(main(['ros']))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=False, cwd=ROOT)
    assert done.returncode == 69, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "pip install 'usar-arm[ros]'" in lines[0], done.stderr
