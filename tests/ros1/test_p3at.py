"""The seed's steps as written, on the P3AT: `roscore`, `roslaunch usarsim usarsim.launch`
(Table 1's parameters), a teleop-style cmd_vel publisher (Debian's `rostopic pub`) moving the
robot; then Debian's tools judge what the node serves: `view_frames` sees the seed's tree
(base_footprint, base_link, the laser frame, odom, the ground truth's own) at the rates the
simulator sends, and robot_state_publisher publishes the node's fixed frames."""

from __future__ import annotations

import json
import math
import re
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from tests.ros1.helpers import Master, client, stop
from tests.ros1.transforms import compare_trees, edges_by_stamp
from usar_arm.ros import ros1_setup

ROBOT_SPEC = Path(ros1_setup.HERE).parent / "sim" / "robots" / "p3at.yaml"
RSP = "/usr/lib/robot_state_publisher/robot_state_publisher"
VIEW_FRAMES = "/usr/lib/tf2_tools/view_frames.py"


@pytest.fixture(scope="module")
def launched(ros1_env: ros1_setup.Ros1Environment, tmp_path_factory: pytest.TempPathFactory
             ) -> Iterator[tuple[Master, Path]]:
    """roscore, then roslaunch usarsim usarsim.launch (on simulated time)."""
    folder = tmp_path_factory.mktemp("ros1-p3at")
    master = Master(ros1_env, folder)
    launch = subprocess.Popen(["roslaunch", "usarsim", "usarsim.launch", "use_sim_time:=true"],
                              env=master.env(), stdout=open(folder / "launch.log", "w"),
                              stderr=subprocess.STDOUT)
    try:
        client(master, "description", "--timeout", "240", timeout=300)
        yield master, folder
    finally:
        code = stop(launch)
        master.close()
        assert code == 0, (folder / "launch.log").read_text()[-3000:]
        assert "Traceback" not in (folder / "launch.log").read_text()


def _truth(master: Master, folder: Path) -> dict[str, float]:
    client(master, "record", "--seconds", "1.0", "--out", str(folder / "gt.json"),
           "/ground_truth:nav_msgs/Odometry")
    got = json.loads((folder / "gt.json").read_text())["/ground_truth"]
    assert got, "no ground_truth"
    pose = got[-1][1]["pose"]["pose"]
    q = pose["orientation"]
    yaw = math.atan2(2 * (q["w"] * q["z"] + q["x"] * q["y"]),
                     1 - 2 * (q["y"] ** 2 + q["z"] ** 2))
    return {"x": pose["position"]["x"], "y": pose["position"]["y"], "yaw": yaw}


def test_a_teleop_publisher_drives_the_robot_the_way_it_is_told(
        launched: tuple[Master, Path]) -> None:
    master, folder = launched
    before = _truth(master, folder)
    teleop = subprocess.Popen(["rostopic", "pub", "-r", "10", "/cmd_vel", "geometry_msgs/Twist",
                               "{linear: {x: 0.1}, angular: {z: 0.0}}"], env=master.env(),
                              stdout=subprocess.DEVNULL, stderr=open(folder / "pub.log", "w"))
    time.sleep(6.0)
    stop(teleop)
    time.sleep(1.5)  # the command timeout stops it
    after = _truth(master, folder)
    heading = (math.cos(before["yaw"]), math.sin(before["yaw"]))
    forward = (after["x"] - before["x"]) * heading[0] + (after["y"] - before["y"]) * heading[1]
    sideways = -(after["x"] - before["x"]) * heading[1] + (after["y"] - before["y"]) * heading[0]
    # 0.1 m/s for 6 s, less rostopic's start and a loaded simulator's slower time: at least
    # a fifth of it, straight
    assert forward > 0.12, (before, after)
    assert abs(sideways) < 0.1 * forward, (before, after)
    still = _truth(master, folder)
    assert math.hypot(still["x"] - after["x"], still["y"] - after["y"]) < 0.01, "it stopped"


def _rates() -> dict[str, float]:
    """The simulator's sensor rates (Hz), from the robot's spec (ScanInterval)."""
    spec = yaml.safe_load(ROBOT_SPEC.read_text())
    sensors = next(v for v in _walk(spec) if isinstance(v, list) and v and
                   isinstance(v[0], dict) and "type" in v[0] and "settings" in v[0])
    return {s["name"]: 1.0 / s["settings"]["ScanInterval"] for s in sensors}


def _walk(node: object) -> Iterator[object]:
    yield node
    if isinstance(node, dict):
        for v in node.values():
            yield from _walk(v)
    elif isinstance(node, list):
        for v in node:
            yield from _walk(v)


def test_view_frames_sees_the_seeds_tree_at_the_simulators_rates(
        launched: tuple[Master, Path]) -> None:
    master, folder = launched
    work = folder / "view_frames"
    work.mkdir()
    done = subprocess.run([str(master.ros1.python), VIEW_FRAMES], env=master.env(), cwd=work,
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    assert (work / "frames.pdf").stat().st_size > 1000, "dot drew the tree"
    dot = (work / "frames.gv").read_text()
    edges = {(a, b): float(rate) for a, b, rate in re.findall(
        r'"([^"]+)" -> "([^"]+)"\[label=" Broadcaster: [^\\]*\\nAverage rate: ([0-9.]+)', dot)}
    for edge in [("odom", "base_footprint"), ("base_footprint", "base_link"),
                 ("base_link", "lms200_link"), ("base_link", "instest_link"),
                 ("truth/map", "truth/base_footprint")]:
        assert edge in edges, f"{edge} not in view_frames' tree: {sorted(edges)}"
    rates = _rates()
    # tf's average rate over its buffer, on simulated time: the sensors' own periods
    assert edges[("odom", "base_footprint")] == pytest.approx(rates["InsTest"], rel=0.1)
    assert edges[("truth/map", "truth/base_footprint")] == pytest.approx(rates["GndTruth"],
                                                                         rel=0.1)
    assert edges[("base_footprint", "base_link")] > 1e3, "static (tf2 reports 10000)"


def test_robot_state_publisher_publishes_the_nodes_fixed_frames(
        launched: tuple[Master, Path]) -> None:
    master, folder = launched
    rsp = subprocess.Popen([RSP, "tf:=/rsp/tf", "tf_static:=/rsp/tf_static", "__name:=rsp"],
                           env=master.env(), stdout=open(folder / "rsp.log", "w"),
                           stderr=subprocess.STDOUT)
    try:
        time.sleep(2.0)
        client(master, "record", "--seconds", "2", "--out", str(folder / "static.json"),
               "/tf_static:tf2_msgs/TFMessage", "/rsp/tf_static:tf2_msgs/TFMessage")
    finally:
        stop(rsp)
    got = json.loads((folder / "static.json").read_text())
    mine = edges_by_stamp(got["/tf_static"], any_stamp=True)[(0, 0)]
    theirs = edges_by_stamp(got["/rsp/tf_static"], any_stamp=True)[(0, 0)]
    wheels = {k for k in mine if k[1].endswith("_wheel")}
    assert len(wheels) == 4, "the node draws the four wheels at rest (UDK sends no wheel state)"
    # robot_state_publisher publishes the URDF's fixed joints (base_footprint -> base_link, the
    # sensor mounts); the node publishes each of them, equal, and the wheels besides.
    assert set(mine) - wheels == set(theirs), set(mine) ^ set(theirs)
    assert compare_trees([(mine, theirs)]) == (pytest.approx(0, abs=1e-9),
                                               pytest.approx(0, abs=1e-9))
