"""``usar-arm drive`` over real TCP against the embedded simulator (rooms world): the P3AT
reaches a waypoint, the bag reads back as ros2 bag / Foxglove read it, the picture is a PNG,
the laser hits placed by the ground truth lie on the world's walls, and bad input gets one
clear line and the exit code of its kind."""

from __future__ import annotations

import json
import math
import struct
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from usar_arm.core.errors import (
    EXIT_INVALID_INPUT,
    EXIT_OK,
    EXIT_UNAVAILABLE,
    EXIT_UNKNOWN_ROBOT,
)

ROOT = Path(__file__).resolve().parents[2]
ROOMS = ROOT / "usar_arm" / "sim" / "worlds" / "rooms.yaml"
START = (0.5, -1.5)
"""RobotStart1 of the rooms world in the map frame (the file says 0.5, 1.5 with y right)."""
GOAL = (1.8, -1.5)
TOPICS = {"/tf_static": "tf2_msgs/msg/TFMessage", "/tf": "tf2_msgs/msg/TFMessage",
          "/odom": "nav_msgs/msg/Odometry", "/ground_truth": "nav_msgs/msg/Odometry",
          "/scan": "sensor_msgs/msg/LaserScan", "/cmd_vel": "geometry_msgs/msg/Twist"}


def usar_arm(*argv: str, cwd: Path, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "usar_arm", *argv], capture_output=True,
                          text=True, cwd=cwd, timeout=timeout, check=False)


@pytest.fixture(scope="module")
def drive(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """One drive to a waypoint 1.3 m ahead, with a bag and a picture (simulator at 4x)."""
    folder = tmp_path_factory.mktemp("drive")
    done = usar_arm("drive", "--robot", "P3AT", "--waypoints", f"{GOAL[0]},{GOAL[1]}",
                    "--speed", "4", "-o", "bag", "--picture", "run.png", "--json", "-q",
                    cwd=folder)
    assert done.returncode == EXIT_OK, done.stderr
    return folder, json.loads(done.stdout)


def test_the_p3at_reaches_a_waypoint_within_the_tolerance(drive: tuple[Path, dict[str, Any]]
                                                         ) -> None:
    folder, result = drive
    assert result["reached"] and not result["interrupted"]
    truth = _read(folder / "bag")["/ground_truth"]
    first, last = truth[0][1].pose.pose.position, truth[-1][1].pose.pose.position
    assert math.dist((last.x, last.y), GOAL) < 0.1 + 0.02  # tolerance, and the roll after STOP
    assert math.dist((first.x, first.y), START) < 0.01
    assert result["distance_m"] == pytest.approx(1.3, abs=0.15)


def test_wheel_commands_stay_within_what_the_vehicle_reported(
        drive: tuple[Path, dict[str, Any]]) -> None:
    commands = drive[1]["commands"]
    assert commands["max_wheel_speed_radps"] == pytest.approx(1.2999)  # CONF MaxSpeed
    assert 0 < commands["largest_sent_radps"] <= commands["max_wheel_speed_radps"]
    assert commands["clamped"] > 0  # 0.5 m/s asked of a 0.127 m/s vehicle


def test_the_bag_reads_back_with_every_topic_its_types_and_increasing_stamps(
        drive: tuple[Path, dict[str, Any]]) -> None:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    bag = drive[0] / "bag"
    assert (bag / "metadata.yaml").is_file() and list(bag.glob("*.mcap"))
    store = get_typestore(Stores.ROS2_HUMBLE)
    with Reader(bag) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types == TOPICS
        counts = {c.topic: c.msgcount for c in reader.connections}  # (from metadata.yaml)
        assert all(c.msgdef.data for c in reader.connections)  # definitions travel in the bag
        stamps: dict[str, list[int]] = {t: [] for t in TOPICS}
        last = 0
        scan: Any = None
        for conn, stamp, raw in reader.messages():
            assert stamp >= last
            last = stamp
            stamps[conn.topic].append(stamp)
            if conn.topic == "/scan" and scan is None:
                scan = store.deserialize_cdr(raw, conn.msgtype)
    assert counts == {topic: len(stamped) for topic, stamped in stamps.items()}
    assert len(stamps["/tf_static"]) == 1
    for topic in ("/tf", "/odom", "/ground_truth", "/scan", "/cmd_vel"):
        assert len(stamps[topic]) > 10, topic
        if topic != "/cmd_vel":  # (the final stop shares the last command's stamp)
            assert np.all(np.diff(stamps[topic]) > 0), topic
    assert scan is not None and scan.header.frame_id == "lms200"
    assert len(scan.ranges) == 181 and scan.range_max == pytest.approx(20.0)
    assert scan.angle_min == pytest.approx(-scan.angle_max)
    assert scan.angle_min + 180 * scan.angle_increment == pytest.approx(scan.angle_max)


def test_the_picture_is_a_png(drive: tuple[Path, dict[str, Any]]) -> None:
    data = (drive[0] / "run.png").read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    width, height = struct.unpack(">II", data[16:24])
    assert width >= 800 and height >= 600


def _read(bag: Path) -> dict[str, list[tuple[int, Any]]]:
    """topic -> [(stamp ns, message)] of a bag, read with rosbags alone."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    out: dict[str, list[tuple[int, Any]]] = {}
    with Reader(bag) as reader:
        for conn, stamp, raw in reader.messages():
            out.setdefault(conn.topic, []).append(
                (stamp, store.deserialize_cdr(raw, conn.msgtype)))
    return out


def _yaw(q: Any) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def _hits(bag: Path) -> tuple[np.ndarray, np.ndarray]:
    """Every laser hit (m, map frame) of the bag, placed by /ground_truth at the scan's stamp
    and the scanner's /tf_static mount, and each hit's range (m)."""
    topics = _read(bag)
    truth = [(t, m.pose.pose) for t, m in topics["/ground_truth"]]
    stamps = np.array([t for t, _ in truth], dtype=float)
    xs = np.array([p.position.x for _, p in truth])
    ys = np.array([p.position.y for _, p in truth])
    yaws = np.unwrap([_yaw(p.orientation) for _, p in truth])
    mount = next(tf.transform.translation for tf in topics["/tf_static"][0][1].transforms
                 if tf.child_frame_id == "lms200")
    points, ranges = [], []
    for stamp, scan in topics["/scan"]:
        r = np.asarray(scan.ranges, dtype=float)
        a = scan.angle_min + np.arange(len(r)) * scan.angle_increment
        keep = r < scan.range_max
        x, y, yaw = (float(np.interp(stamp, stamps, v)) for v in (xs, ys, yaws))
        lx, ly = mount.x + r[keep] * np.cos(a[keep]), mount.y + r[keep] * np.sin(a[keep])
        points.append(np.stack([x + math.cos(yaw) * lx - math.sin(yaw) * ly,
                                y + math.sin(yaw) * lx + math.cos(yaw) * ly], axis=1))
        ranges.append(r[keep])
    return np.concatenate(points), np.concatenate(ranges)


def _tall_boxes(scan_height: float) -> list[tuple[float, float, float, float, float]]:
    """(cx, cy, hx, hy, yaw) in the map frame of every box of rooms.yaml whose top is above
    the scan plane, read here with PyYAML alone."""
    boxes = yaml.safe_load(ROOMS.read_text())["boxes"]
    return [(b["center"][0], -b["center"][1], b["half"][0], b["half"][1], -b.get("yaw", 0.0))
            for b in boxes if -(b["center"][2] - b["half"][2]) > scan_height]


def _distance_to_box(p: np.ndarray, box: tuple[float, float, float, float, float]
                     ) -> np.ndarray:
    cx, cy, hx, hy, yaw = box
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = p[:, 0] - cx, p[:, 1] - cy
    u, v = np.abs(c * dx + s * dy) - hx, np.abs(-s * dx + c * dy) - hy
    outside = np.hypot(np.maximum(u, 0), np.maximum(v, 0))
    return np.where((u <= 0) & (v <= 0), -np.minimum(-u, -v), outside)


def test_laser_hits_placed_by_ground_truth_lie_on_the_walls(
        drive: tuple[Path, dict[str, Any]]) -> None:
    """Each hit within the printed precision of a tall box's surface: ranges are truncated to
    0.01 m, poses to 1 mm and 0.001 rad, the mount to 1 mm, ray angles are off by < 0.001 rad
    (Unreal angle units against the printed FOV)."""
    hits, reach = _hits(drive[0] / "bag")
    assert len(hits) > 1000
    tolerance = 0.01 + 0.003 + 0.002 * reach
    distance = np.min([np.abs(_distance_to_box(hits, b)) for b in _tall_boxes(0.3)], axis=0)
    worst = int(np.argmax(distance - tolerance))
    assert np.all(distance <= tolerance), \
        f"hit {hits[worst]} is {distance[worst]:.4f} m from every wall (allowed " \
        f"{tolerance[worst]:.4f} m)"


def test_render_world_draws_the_world_file_alone(tmp_path: Path) -> None:
    done = usar_arm("render", "--world", "rooms", "--out", "rooms.png", cwd=tmp_path)
    assert done.returncode == EXIT_OK, done.stderr
    assert (tmp_path / "rooms.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "13 boxes" in done.stdout


@pytest.mark.parametrize(("argv", "code", "says"), [
    (["--robot", "NoSuchBot", "--waypoints", "1,-1.5"], EXIT_UNKNOWN_ROBOT, "NoSuchBot"),
    (["--waypoints", "40,2"], EXIT_INVALID_INPUT, "waypoint 1 (40, 2) m lies outside"),
    (["--waypoints", "1,-1.5", "2.5,-1.5"], EXIT_INVALID_INPUT, "inside box"),
    (["--waypoints", "1;2"], EXIT_INVALID_INPUT, "neither x,y nor a file"),
    (["--waypoints", "1,2,3"], EXIT_INVALID_INPUT, "expected x,y in metres"),
    (["--script", "bad.yaml"], EXIT_INVALID_INPUT, "bad.yaml:2"),
    (["--script", "bad.csv"], EXIT_INVALID_INPUT, "bad.csv:3"),
])
def test_bad_input_gets_one_line_and_its_exit_code(tmp_path: Path, argv: list[str], code: int,
                                                   says: str) -> None:
    (tmp_path / "bad.yaml").write_text("- [1.0, 0.1, 0.0]\n- [1.0, fast, 0.0]\n")
    (tmp_path / "bad.csv").write_text("duration,v,w\n1,0.1,0\n-1,0.1,0\n")
    done = usar_arm("drive", *argv, cwd=tmp_path, timeout=60)
    assert done.returncode == code, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("usar-arm: error:") and says in lines[0]
    assert not (tmp_path / "drive.png").exists()


def test_an_arm_is_refused_as_no_ground_vehicle(tmp_path: Path) -> None:
    done = usar_arm("drive", "--robot", "KR60", "--waypoints", "1,-1.5", cwd=tmp_path)
    assert done.returncode == EXIT_INVALID_INPUT, done.stderr
    assert "USARBot.KR60 is a StaticPlatform, not a ground vehicle" in done.stderr


def test_a_velocity_script_is_played_and_recorded(tmp_path: Path) -> None:
    (tmp_path / "s.csv").write_text("duration,v,w\n3,0.1,0\n3,0,0.5\n")
    done = usar_arm("drive", "--script", "s.csv", "--speed", "4", "-o", "bag", "--picture", "",
                    "--json", "-q", cwd=tmp_path)
    assert done.returncode == EXIT_OK, done.stderr
    result = json.loads(done.stdout)
    assert result["reached"] and result["written"] == {"bag": "bag"}
    assert result["duration_s"] == pytest.approx(6.0, abs=0.3)
    assert 0.2 < result["distance_m"] < 0.35  # 3 s at 0.1 m/s, then a turn on the spot
    commands = [m for _, m in _read(tmp_path / "bag")["/cmd_vel"]]
    assert {(c.linear.x, c.angular.z) for c in commands} == {(0.1, 0.0), (0.0, 0.5),
                                                              (0.0, 0.0)}
    assert (commands[-1].linear.x, commands[-1].angular.z) == (0.0, 0.0)


def test_ctrl_c_stops_the_vehicle_and_keeps_the_record(tmp_path: Path,
                                                       ctrl_c_reaches_children: None) -> None:
    """SIGINT mid-drive: exit 130, the bag and the picture are written, the last command
    sent is a stop."""
    import signal
    import time

    proc = subprocess.Popen([sys.executable, "-m", "usar_arm", "drive", "--waypoints", "4,-1",
                             "-o", "bag"], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    seen = [proc.stderr.readline() for _ in range(1)]
    while "%" not in seen[-1] and seen[-1] and len(seen) < 50:  # (a warning may come first)
        seen.append(proc.stderr.readline())
    assert "%" in seen[-1], seen  # the progress bar's first line: the drive has begun
    time.sleep(1.5)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "interrupted" in stderr and "wrote bag bag" in stdout
    assert (tmp_path / "drive.png").is_file()
    commands = [m for _, m in _read(tmp_path / "bag")["/cmd_vel"]]
    assert len(commands) >= 2 and commands[0].linear.x > 0
    assert (commands[-1].linear.x, commands[-1].angular.z) == (0.0, 0.0)


def test_a_running_server_is_driven_through_host_and_port(tmp_path: Path) -> None:
    from usar_arm.sim.server import SimOptions, SimServer
    from usar_arm.sim.world_spec import load_world

    server = SimServer(SimOptions(port=0, speed=4.0), world_spec=load_world("rooms"))
    port = server.start()
    try:
        done = usar_arm("drive", "--host", "127.0.0.1", "--port", str(port), "--waypoints",
                        "1.0,-1.5", "--start-position", "RobotStart1", "--json", "-q",
                        cwd=tmp_path)
    finally:
        server.stop()
    assert done.returncode == EXIT_OK, done.stderr
    assert json.loads(done.stdout)["reached"]


def test_an_unreachable_server_gets_one_line_and_exit_69(tmp_path: Path) -> None:
    import socket

    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    done = usar_arm("drive", "--host", "127.0.0.1", "--port", str(port), "--waypoints",
                    "1,-1.5", "--timeout", "2", cwd=tmp_path)
    assert done.returncode == EXIT_UNAVAILABLE, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_the_drive_can_steer_on_the_ins(tmp_path: Path) -> None:
    done = usar_arm("drive", "--waypoints", "1.5,-1.5", "--localisation", "ins", "--speed", "4",
                    "--picture", "", "--json", "-q", cwd=tmp_path)
    assert done.returncode == EXIT_OK, done.stderr
    result = json.loads(done.stdout)
    assert result["reached"] and result["distance_m"] == pytest.approx(0.9, abs=0.12)


@pytest.mark.slow
def test_a_loop_of_about_20_m_reports_the_drift_of_odometry_and_ins(tmp_path: Path) -> None:
    """The loop of docs/platform.md: the shipped INS (no noise) stays within centimetres; the
    skid-steered odometry counts every turn as rolling and drifts by metres."""
    done = usar_arm("drive", "--start-position", "RobotStart2", "--waypoints", "7,-5",
                    "10.25,-5", "10.25,0", "5.75,0", "5.75,-5", "7,-5", "--speed", "6",
                    "--picture", "", "--json", "-q", cwd=tmp_path, timeout=600)
    assert done.returncode == EXIT_OK, done.stderr
    result = json.loads(done.stdout)
    assert result["reached"] and 17 < result["distance_m"] < 21
    assert result["drift"]["INS"]["position_m"] < 0.05
    assert result["drift"]["odometry"]["position_m"] > 0.5
    assert result["commands"]["largest_sent_radps"] <= result["commands"][
        "max_wheel_speed_radps"]
