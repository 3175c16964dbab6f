"""Both middlewares agree: one recorded simulator session (a node's, through a relay to
`usar-arm sim`) replayed into the ROS 2 node and into the ROS 1 node; on simulated time, both
publish the same joint states, transforms and scans, field by field. So what the real ROS 1
tools say of the ROS 1 node (the other tests here) holds for the ROS 2 node, which no real ROS 2
tool can consume on this machine."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed: pip install "
                                    "'usar-arm[ros]'")

from usar_arm.ros import build

build.setup()  # the ROS 2 message build (tf2_msgs), as tests/ros's conftest makes it
build.ensure_importable()

from nav_msgs.msg import Odometry  # noqa: E402
from sensor_msgs.msg import JointState, LaserScan  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402

from tests.ros.helpers import Client, NodeProcess, domain_id  # noqa: E402
from tests.ros1.helpers import Master, Node, client  # noqa: E402
from tests.ros1.replay import Recorder, Recording, Replayer  # noqa: E402
from usar_arm.ros import ros1_setup  # noqa: E402

STREAM_S = 30.0
"""How long the recorded node streams after it has served its description (s)."""
WINDOW_S = STREAM_S
"""How long each replayed node is listened to from its description on: to the end of the
stream, so the two windows share all but what one node's slower start costs (the stream's
pace is anchored at the last request; a node then takes 3 to 11 s to serve here)."""
TOPICS = {"KR60": {"joint_states": "sensor_msgs/JointState", "tf": "tf2_msgs/TFMessage"},
          "P3AT": {"scan": "sensor_msgs/LaserScan", "odom": "nav_msgs/Odometry",
                   "tf": "tf2_msgs/TFMessage"}}
ROS2_TYPES = {"sensor_msgs/JointState": JointState, "tf2_msgs/TFMessage": TFMessage,
              "sensor_msgs/LaserScan": LaserScan, "nav_msgs/Odometry": Odometry}


def _simulator(folder: Path, world: str) -> tuple[subprocess.Popen[bytes], int]:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = int(s.getsockname()[1])
    proc = subprocess.Popen([sys.executable, "-m", "usar_arm", "sim", "--port", str(port),
                             "--world", world], stdout=open(folder / "sim.log", "w"),
                            stderr=subprocess.STDOUT)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
            return proc, port
        except OSError:
            time.sleep(0.1)
    raise RuntimeError("usar-arm sim did not listen")


def _ros2(robot: str, port: int, folder: Path, name: str, seconds: float
          ) -> dict[str, list[Any]]:
    """A ROS 2 node on ``port`` (simulated time, a fresh description cache): what it published
    on the robot's topics for ``seconds`` after its description."""
    domain = domain_id()
    node = NodeProcess(domain, ["--robot", robot, "--host", "127.0.0.1", "--port", str(port),
                                "--use-sim-time", "-v"], folder / f"{name}.log",
                       USAR_ARM_CACHE=str(folder / f"{name}-cache"))
    ros = Client(domain)
    try:
        ros.description(timeout=240)
        got = ros.collect_many({t: ROS2_TYPES[k] for t, k in TOPICS[robot].items()}, seconds)
    finally:
        ros.close()
        code = node.stop()
    assert code == 0, node.text()[-3000:]
    return {topic: [m for _, m in msgs] for topic, msgs in got.items()}


def _record(robot: str, folder: Path) -> Recording:
    sim, port = _simulator(folder, "rooms" if robot == "P3AT" else "default")
    recorder = Recorder("127.0.0.1", port)
    try:
        _ros2(robot, recorder.port, folder, "recorded", STREAM_S)
    finally:
        recording = recorder.close()
        sim.terminate()
        sim.wait(30)
    return recording


def _stamp(msg: Any) -> tuple[int, int]:
    stamp = msg.header.stamp
    return (stamp.sec, stamp.nanosec)


def _ros2_fields(topic: str, msg: Any) -> Any:
    if topic == "joint_states":
        return [list(msg.name), list(msg.position), list(msg.velocity)]
    if topic == "scan":
        return [msg.header.frame_id, msg.angle_min, msg.angle_max, msg.angle_increment,
                msg.range_min, msg.range_max, msg.scan_time, [float(r) for r in msg.ranges]]
    if topic == "odom":
        p, t = msg.pose.pose, msg.twist.twist
        return [msg.header.frame_id, msg.child_frame_id,
                [p.position.x, p.position.y, p.position.z],
                [p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w],
                [t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z]]
    return sorted([t.header.frame_id, t.child_frame_id, [t.header.stamp.sec,
                   t.header.stamp.nanosec],
                   [t.transform.translation.x, t.transform.translation.y,
                    t.transform.translation.z],
                   [t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
                    t.transform.rotation.w]] for t in msg.transforms)


def _ros1_fields(topic: str, msg: dict[str, Any]) -> Any:
    if topic == "joint_states":
        return [msg["name"], msg["position"], msg["velocity"]]
    if topic == "scan":
        return [msg["header"]["frame_id"], msg["angle_min"], msg["angle_max"],
                msg["angle_increment"], msg["range_min"], msg["range_max"], msg["scan_time"],
                msg["ranges"]]
    if topic == "odom":
        p, t = msg["pose"]["pose"], msg["twist"]["twist"]
        return [msg["header"]["frame_id"], msg["child_frame_id"],
                [p["position"][k] for k in "xyz"], [p["orientation"][k] for k in "xyzw"],
                [t["linear"][k] for k in "xyz"] + [t["angular"][k] for k in "xyz"]]
    return sorted([t["header"]["frame_id"], t["child_frame_id"], t["header"]["stamp"],
                   [t["transform"]["translation"][k] for k in "xyz"],
                   [t["transform"]["rotation"][k] for k in "xyzw"]] for t in msg["transforms"])


def _close(a: Any, b: Any, tolerance: float) -> bool:
    """Equal, numbers within ``tolerance`` (0: exactly)."""
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y, tolerance) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        return abs(a - b) <= tolerance
    return bool(a == b)


TOLERANCE = {"odom": 1e-12, "tf": 1e-12}
"""The odom frame is where base_footprint stood at the first INS reading each node saw, which
depends on how long each took to start (a standing robot's readings differ by the INS's
rounding, 1e-19 here); every other field is compared exactly."""


def _by_stamp(messages: list[Any], fields: Any, stamp: Any) -> dict[Any, Any]:
    return {stamp(m): fields(m) for m in messages}


def _tf_key(fields: Any) -> Any:
    return lambda m: json.dumps([e[:3] for e in fields("tf", m)])


@pytest.mark.slow  # (about 2 minutes per robot: make test-slow and CI run it)
@pytest.mark.parametrize("robot", ["KR60", "P3AT"])
def test_one_session_replayed_into_both_nodes_gives_the_same_messages(
        robot: str, ros1_env: ros1_setup.Ros1Environment, tmp_path: Path) -> None:
    recording = _record(robot, tmp_path)
    replay2 = Replayer(recording)
    try:
        ros2 = _ros2(robot, replay2.port, tmp_path, "ros2", WINDOW_S)
    finally:
        replay2.close()
    replay1 = Replayer(recording)
    master = Master(ros1_env, tmp_path)
    node = Node(master, ["--robot", robot, "--host", "127.0.0.1", "--port", str(replay1.port),
                         "--use-sim-time", "-v"], tmp_path / "ros1.log",
                USAR_ARM_CACHE=str(tmp_path / "ros1-cache"))
    try:
        client(master, "description", "--timeout", "240", timeout=300)
        client(master, "record", "--seconds", str(WINDOW_S), "--out",
               str(tmp_path / "ros1.json"), *(f"/{t}:{k}" for t, k in TOPICS[robot].items()))
    finally:
        code = node.stop()
        master.close()
        replay1.close()
    assert code == 0, node.text()[-3000:]
    assert not replay1.mismatches and not replay2.mismatches, "both asked what was recorded"
    ros1 = json.loads((tmp_path / "ros1.json").read_text())
    for topic in TOPICS[robot]:
        if topic == "tf":  # a message by its transforms' frames and stamps
            two = _by_stamp(ros2[topic], lambda m: _ros2_fields("tf", m), _tf_key(_ros2_fields))
            one = _by_stamp([m for _, m in ros1["/tf"]], lambda m: _ros1_fields("tf", m),
                            _tf_key(_ros1_fields))
            shared = sorted(set(two) & set(one))
            assert len(shared) >= 10, f"tf: only {len(shared)} messages in both windows"
            for key in shared:
                assert _close(json.loads(json.dumps(two[key])), one[key],
                              TOLERANCE["tf"] if robot == "P3AT" else 0.0), key
            continue
        two = _by_stamp(ros2[topic], lambda m, t=topic: _ros2_fields(t, m), _stamp)
        one = _by_stamp([m for _, m in ros1[f"/{topic}"]],
                        lambda m, t=topic: _ros1_fields(t, m),
                        lambda m: tuple(m["header"]["stamp"]))
        # a node's first scan has no period yet (scan_time 0) and its first odometry no twist:
        # what each node saw first depends on how long it took to start, so those are left out
        first = set(list(two)[:2]) | {tuple(m["header"]["stamp"]) for _, m in
                                      ros1[f"/{topic}"][:2]}
        shared = sorted((set(two) & set(one)) - first)
        assert len(shared) >= 10, f"{topic}: only {len(shared)} messages in both windows"
        for stamp in shared:
            assert _close(json.loads(json.dumps(two[stamp])), one[stamp],
                          TOLERANCE.get(topic, 0.0)), (topic, stamp, two[stamp], one[stamp])
