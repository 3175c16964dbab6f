"""`usar-arm ros` against a separate simulator process: settings given as ROS parameters, two
robots of one world under two namespaces, simulated time, a simulator killed mid-goal, and
Ctrl-C ending the node with exit 0."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed: pip install "
                                    "'usar-arm[ros]'")

from action_msgs.msg import GoalStatus
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage

from tests.ros.helpers import LATCHED, Client, NodeProcess, domain_id, make_goal

NAMES = [f"joint_a{i}" for i in range(1, 7)]
ACTION = "KR60Arm_controller/follow_joint_trajectory"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture
def simulator(tmp_path: Path) -> Iterator[tuple[subprocess.Popen[bytes], int]]:
    port = _free_port()
    log = open(tmp_path / "sim.log", "w")
    proc = subprocess.Popen([sys.executable, "-m", "usar_arm", "sim", "--port", str(port)],
                            stdout=log, stderr=subprocess.STDOUT, env=dict(os.environ))
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
            break
        except OSError:
            time.sleep(0.1)
    yield proc, port
    if proc.poll() is None:
        proc.terminate()
        proc.wait(20)
    log.close()


def _joints(client: Client, topic: str = "joint_states") -> np.ndarray:
    got = client.collect(JointState, topic, 5.0, until=bool)
    assert got, f"no {topic}"
    return np.array(got[-1][1].position)


def test_two_robots_of_one_world_under_two_namespaces(
        simulator: tuple[subprocess.Popen[bytes], int], tmp_path: Path) -> None:
    _, port = simulator
    domain = domain_id()
    params = ["-p", "host:=127.0.0.1", "-p", f"port:={port}"]
    one = NodeProcess(domain, ["--ros-args", "-r", "__ns:=/r1", *params], tmp_path / "r1.log")
    two = NodeProcess(domain, ["--use-sim-time", "--ros-args", "-r", "__ns:=/r2", *params,
                               "-p", "start:=RobotStart2"], tmp_path / "r2.log")
    client = Client(domain)
    try:
        # the same arm: equal but for the header comment, which names each one's start
        # position (RobotStart1, RobotStart2) when each learnt its own description
        one_text, two_text = (re.sub(r"<!--.*?-->", "", client.description(f"/{ns}/"
                                                                         "robot_description"),
                                     flags=re.S) for ns in ("r1", "r2"))
        assert one_text == two_text
        static = {m.transforms[0].child_frame_id: m for _, m in
                  [client.collect(TFMessage, f"/{ns}/tf_static", 10.0, LATCHED, until=bool)[0]
                   for ns in ("r1", "r2")]}
        assert len(static) == 1  # both name their root base_link...
        stands = [client.collect(TFMessage, f"/{ns}/tf_static", 10.0, LATCHED,
                                 until=bool)[0][1].transforms[0].transform.translation
                  for ns in ("r1", "r2")]
        assert abs(stands[0].x) < 0.011 and abs(stands[1].x - 4.0) < 0.011  # ...apart
        got = client.collect_many({"/clock": Clock, "/r2/joint_states": JointState,
                                   "/r1/joint_states": JointState}, 3.0)
        assert len(got["/clock"]) >= 10, "r2 publishes /clock from the simulator"
        sim_times = {(c.clock.sec, c.clock.nanosec) for _, c in got["/clock"]}
        stamps = [(m.header.stamp.sec, m.header.stamp.nanosec)
                  for _, m in got["/r2/joint_states"]]
        assert len(stamps) >= 10 and all(s in sim_times for s in stamps), \
            "r2 stamps with the simulator's time"
        steps = np.diff([sec + nsec * 1e-9 for sec, nsec in stamps])
        assert np.allclose(steps, 0.1, atol=1e-3), f"an ASTA line was skipped: {steps}"
        assert all(m.header.stamp.sec > 1e9 for _, m in got["/r1/joint_states"]), \
            "r1 stamps with the system's time"
        before1, before2 = _joints(client, "/r1/joint_states"), \
            _joints(client, "/r2/joint_states")
        handle = client.send(f"/r1/{ACTION}", make_goal(NAMES, [(1.5, before1 + 0.2)]))
        status, result = client.result(handle)
        assert status == GoalStatus.STATUS_SUCCEEDED, result.error_string
        assert np.max(np.abs(_joints(client, "/r1/joint_states") - before1 - 0.2)) < 0.002
        assert np.max(np.abs(_joints(client, "/r2/joint_states") - before2)) < 0.002
    finally:
        client.close()
        codes = (one.stop(signal.SIGINT), two.stop(signal.SIGTERM))
    assert codes == (0, 0), one.text()[-2000:] + two.text()[-2000:]


def test_a_simulator_killed_mid_goal_aborts_the_goal_and_the_node_lives_on(
        simulator: tuple[subprocess.Popen[bytes], int], tmp_path: Path) -> None:
    sim, port = simulator
    domain = domain_id()
    node = NodeProcess(domain, ["--host", "127.0.0.1", "--port", str(port)],
                       tmp_path / "node.log")
    client = Client(domain)
    try:
        client.description()
        q0 = _joints(client)
        handle = client.send(ACTION, make_goal(NAMES, [(6.0, q0 + 0.3)]))
        time.sleep(1.5)
        sim.kill()
        status, result = client.result(handle, timeout=30)
        assert status == GoalStatus.STATUS_ABORTED
        assert "connection" in result.error_string, result.error_string
        again = client.send(ACTION, make_goal(NAMES, [(2.0, q0)]))
        status, result = client.result(again, timeout=30)
        assert status == GoalStatus.STATUS_ABORTED
        assert "lost" in result.error_string or "connection" in result.error_string, \
            result.error_string
        assert node.proc.poll() is None, "the node is still up"
    finally:
        client.close()
        code = node.stop(signal.SIGINT)
    assert code == 0, node.text()[-3000:]


def test_sigterm_during_a_goal_stops_the_motion_and_exits_0(tmp_path: Path) -> None:
    domain = domain_id()
    node = NodeProcess(domain, ["-v"], tmp_path / "node.log")
    client = Client(domain)
    try:
        client.description()
        q0 = _joints(client)
        handle = client.send(ACTION, make_goal(NAMES, [(8.0, q0 + 0.4)]))
        time.sleep(1.5)
        began = time.monotonic()
        code = node.stop(signal.SIGTERM)
        took = time.monotonic() - began
        del handle
    finally:
        client.close()
    assert code == 0, node.text()[-3000:]
    assert "the node is shutting down" in node.text(), node.text()[-3000:]
    assert "Traceback" not in node.text(), node.text()[-3000:]
    assert took < 10.0, f"{took:.1f} s from SIGTERM to exit"
