"""`usar-arm ros --robot P3AT` in another process, read and driven by a real rclpy client:
description, static and moving frames, scan, odom, ground truth, /clock; cmd_vel moves the
robot the way it was told, the command timeout stops it, a NaN command is refused."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed: pip install "
                                    "'usar-arm[ros]'")

from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from tf2_msgs.msg import TFMessage

from tests.ros.helpers import (
    LATCHED,
    Client,
    NodeProcess,
    domain_id,
    latest_odometry,
    moved_under_nan,
    node_session,
    pose_change,
)
from tests.ros.helpers import odometry_yaw as _yaw
from tests.ros.helpers import publish_twist as _drive


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Client, str, NodeProcess]]:
    """A P3AT node on sim time and a client on their own domain; the node must stop with exit
    0 on SIGTERM."""
    with node_session(tmp_path_factory.mktemp("ros-platform"),
                      ["--robot", "P3AT", "--use-sim-time", "-v"]) as started:
        yield started


def _truth(client: Client, seconds: float = 1.0, topic: str = "ground_truth") -> Any:
    return latest_odometry(client, topic, seconds)


def test_description_and_static_frames(session: tuple[Client, str, NodeProcess]) -> None:
    client, urdf, _ = session
    for name in ("base_footprint", "front_left_wheel_joint", "rear_right_wheel_joint",
                 "lms200_link"):
        assert f'"{name}"' in urdf
    got = client.collect(TFMessage, "tf_static", 10.0, LATCHED, until=lambda ms: bool(ms))
    edges = {(t.header.frame_id, t.child_frame_id): t.transform for t in got[0][1].transforms}
    assert edges[("base_footprint", "base_link")].translation.z == pytest.approx(0.098)
    scanner = edges[("base_link", "lms200_link")].translation
    assert (scanner.x, scanner.y, scanner.z) == pytest.approx((0.208, 0.0, 0.2))
    assert {("base_link", "instest_link"), ("base_link", "gndtruth_link")} <= set(edges)


def test_scan_odom_truth_tf_and_clock(session: tuple[Client, str, NodeProcess]) -> None:
    client, _, _ = session
    got = client.collect_many({"scan": LaserScan, "odom": Odometry, "ground_truth": Odometry,
                               "tf": TFMessage, "/clock": Clock}, 1.5)
    scans = [msg for _, msg in got["scan"]]
    assert len(scans) >= 4  # 5 Hz
    scan = scans[-1]
    assert scan.header.frame_id == "lms200_link" and len(scan.ranges) == 181
    assert scan.angle_min == pytest.approx(-3.1414 / 2) and scan.angle_increment == \
        pytest.approx(0.0174)
    assert scan.angle_max == pytest.approx(scan.angle_min + 180 * scan.angle_increment)
    assert (scan.range_min, scan.range_max) == pytest.approx((0.1, 20.0))
    assert scan.scan_time == pytest.approx(0.2, abs=0.02)
    assert all(0.0 < r <= 20.0 for r in scan.ranges)
    odom = got["odom"][-1][1]
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_footprint")
    truth = got["ground_truth"][-1][1]
    assert (truth.header.frame_id, truth.child_frame_id) == ("truth/map", "truth/base_footprint")
    pairs = {(t.header.frame_id, t.child_frame_id) for _, m in got["tf"] for t in m.transforms}
    assert {("odom", "base_footprint"), ("truth/map", "truth/base_footprint")} <= pairs
    clocks = [c.clock.sec + c.clock.nanosec * 1e-9 for _, c in got["/clock"]]
    assert len(clocks) >= 10 and clocks == sorted(clocks)
    assert odom.header.stamp.sec + odom.header.stamp.nanosec * 1e-9 == pytest.approx(
        clocks[-1], abs=0.5)  # stamped with the simulator's time


def test_cmd_vel_moves_forward_and_turns_left_then_the_timeout_stops_it(
        session: tuple[Client, str, NodeProcess]) -> None:
    client, _, node = session
    start, odom_start = _truth(client), _truth(client, topic="odom")
    _drive(client, 0.1, 0.0, 2.0)
    moved, odom = _truth(client), _truth(client, topic="odom")
    heading = _yaw(start)
    dx = moved.pose.pose.position.x - start.pose.pose.position.x
    dy = moved.pose.pose.position.y - start.pose.pose.position.y
    forward = dx * math.cos(heading) + dy * math.sin(heading)
    assert forward > 0.1, (dx, dy, heading)
    # odom (the INS) saw the same move: forward along its x, which starts on the heading
    odom_dx = odom.pose.pose.position.x - odom_start.pose.pose.position.x
    odom_dy = odom.pose.pose.position.y - odom_start.pose.pose.position.y
    assert odom_dx == pytest.approx(forward, abs=0.03) and abs(odom_dy) < 0.03
    _drive(client, 0.0, 0.5, 1.5)  # counter-clockwise (REP-103): the yaw grows
    turned = _truth(client)
    assert math.remainder(_yaw(turned) - _yaw(moved), math.tau) > 0.1
    time.sleep(1.0)  # no command for twice the 0.5 s timeout: stopped
    a = _truth(client)
    time.sleep(0.5)
    b = _truth(client)
    dx, _, dyaw = pose_change(a, b)
    assert abs(dx) < 0.005 and abs(dyaw) < 0.01
    assert "no cmd_vel for 0.5 s: the robot stops" in node.text()


def test_a_nan_command_is_refused_and_the_robot_stops(
        session: tuple[Client, str, NodeProcess]) -> None:
    """NaN commands keep arriving (so the timeout never fires): only refusing them stops it."""
    client, _, node = session
    dx, dy = moved_under_nan(client, 0.1)
    assert abs(dx) < 0.005 and abs(dy) < 0.005
    assert "cmd_vel refused, the robot stops" in node.text()


def test_seed_frames_and_wheel_odometry(tmp_path: Path) -> None:
    """--frames seed (the 2012 names) with odom from the Odometry sensor: odom -> base_link,
    sensors under their USARSim names, no base_footprint."""
    domain = domain_id()
    node = NodeProcess(domain, ["--robot", "P3AT", "--frames", "seed", "--ros-args", "-p",
                                "odom_sensor:=Odometer"], tmp_path / "node.log")
    client = Client(domain)
    try:
        urdf = client.description()
        assert '"base_footprint"' not in urdf and '"lms200"' in urdf
        got = client.collect_many({"scan": LaserScan, "odom": Odometry}, 1.0)
        static = client.collect(TFMessage, "tf_static", 10.0, LATCHED, until=lambda ms: bool(ms))
    finally:
        client.close()
        code = node.stop()
    assert code == 0, node.text()[-3000:]
    assert "odom (from Odometer)" in node.text()
    assert got["scan"][-1][1].header.frame_id == "lms200"
    odom = got["odom"][-1][1]
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
    pairs = {(t.header.frame_id, t.child_frame_id) for t in static[0][1].transforms}
    wheels = {("base_link", f"{end}_{side}_wheel") for end in ("front", "rear")
              for side in ("left", "right")}  # at rest: UDK sends no wheel state
    assert pairs == {("base_link", "GndTruth"), ("base_link", "InsTest"),
                     ("base_link", "lms200")} | wheels


def test_an_arms_option_with_a_vehicle_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    from usar_arm.cli.main import main

    assert main(["ros", "--robot", "P3AT", "--controller", "x"]) == 65
    assert "--controller is an arm's option; P3AT is a ground vehicle" in capsys.readouterr().err
