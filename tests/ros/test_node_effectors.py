"""The KR60's effectors on `usar-arm ros` (a separate `usar-arm sim`, so that this process can
put a crate under the vacuum through the WorldController): the seed's usarsim_inf topics
(status per EFF line, the command topic's SET and its gate, the tool changer's detach) and
the gripper as a control_msgs GripperCommand action, whose result says whether a part is held
by the simulator's GripTruth extension. Sent by a real rclpy client from this process."""

from __future__ import annotations

import math
import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed: pip install "
                                    "'usar-arm[ros]'")

from action_msgs.msg import GoalStatus
from control_msgs.action import GripperCommand
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage
from usarsim_inf.msg import EffectorCommand, EffectorStatus, ToolchangerStatus

from tests.ros.helpers import LATCHED, Client, NodeProcess, domain_id, make_goal
from tests.sim.cell_helpers import changer_pose
from usar_arm.usarsim.world_controller import WorldControllerClient

GRIPPER, CHANGER = "KR60gripper", "toolchange"
ACTION = f"{GRIPPER}/gripper_cmd"
NAMES = [f"joint_a{i}" for i in range(1, 7)]
OPEN, CLOSE = EffectorStatus.OPEN, EffectorStatus.CLOSE


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def cell(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Client, int]]:
    """A simulator, the node on it (the arm at its zero pose) and a client."""
    folder = tmp_path_factory.mktemp("ros-effectors")
    port = _free_port()
    sim_log = open(folder / "sim.log", "w")
    sim = subprocess.Popen([sys.executable, "-m", "usar_arm", "sim", "--port", str(port)],
                           stdout=sim_log, stderr=subprocess.STDOUT, env=dict(os.environ))
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
            break
        except OSError:
            time.sleep(0.1)
    domain = domain_id()
    node = NodeProcess(domain, ["--host", "127.0.0.1", "--port", str(port), "-v",
                                "--ros-args", "-p", "gripper_joint_states:=true"],
                       folder / "node.log")
    client = Client(domain)
    try:
        client.description()
        handle = client.send("KR60Arm_controller/follow_joint_trajectory",
                             make_goal(NAMES, [(2.0, [0.0] * 6)]))
        status, result = client.result(handle)
        assert status == GoalStatus.STATUS_SUCCEEDED, result.error_string
        yield client, port
    finally:
        client.close()
        code = node.stop()
        sim.terminate()
        sim.wait(20)
        sim_log.close()
        assert code == 0, node.text()[-3000:]


def grip(client: Client, position: float, max_effort: float = 0.0) -> tuple[int, object]:
    goal = GripperCommand.Goal()
    goal.command.position, goal.command.max_effort = position, max_effort
    handle = client.send(ACTION, goal, kind=GripperCommand)
    assert handle.accepted
    return client.result(handle, timeout=10.0)


def statuses(client: Client, topic: str, kind: object, seconds: float = 1.0) -> list:
    return [msg for _, msg in client.collect(kind, topic, seconds)]


def test_status_topics_follow_each_eff_line(cell) -> None:
    client, _ = cell
    got = client.collect_many({f"{GRIPPER}/status": EffectorStatus,
                               f"{CHANGER}/status": ToolchangerStatus}, 1.0)
    grippers = [msg for _, msg in got[f"{GRIPPER}/status"]]
    changers = [msg for _, msg in got[f"{CHANGER}/status"]]
    assert 6 <= len(grippers) <= 13 and 6 <= len(changers) <= 13  # 10 Hz EFF lines
    assert {(m.header.frame_id, m.state) for m in grippers} == {(GRIPPER, OPEN)}
    last = changers[-1]
    assert (last.header.frame_id, last.effector_status.state, last.effector_status.header
            .frame_id) == (CHANGER, CLOSE, CHANGER)
    assert (last.tool_type.type, last.tool_name) == (1, GRIPPER)  # ToolType Gripper -> 1


def test_the_tools_frames_are_static_and_the_suction_joint_is_a_joint_state(cell) -> None:
    client, _ = cell
    static = client.collect(TFMessage, "tf_static", 10.0, LATCHED, until=bool)
    edges = {(t.header.frame_id, t.child_frame_id) for t in static[0][1].transforms}
    assert {("link_6", CHANGER), (CHANGER, GRIPPER), (GRIPPER, f"{GRIPPER}_tcp")} <= edges
    states = [msg for _, msg in client.collect(JointState, "joint_states", 1.0)]
    suction = [m for m in states if list(m.name) == [f"{GRIPPER}_suction"]]
    arm = [m for m in states if list(m.name) == NAMES]
    assert len(suction) >= 5 and len(arm) >= 5 and len(suction) + len(arm) == len(states)
    assert {tuple(m.position) for m in suction} == {(0.0,)}  # the vacuum is off


def test_close_over_nothing_succeeds_and_says_nothing_is_held(cell) -> None:
    client, _ = cell
    status, result = grip(client, 1.0)
    assert status == GoalStatus.STATUS_SUCCEEDED
    assert (result.position, result.reached_goal, result.stalled) == (1.0, True, False)
    assert statuses(client, f"{GRIPPER}/status", EffectorStatus, 0.5)[-1].state == CLOSE
    suction = client.collect(JointState, "joint_states", 1.0,
                             until=lambda ms: any(m.name[0] == f"{GRIPPER}_suction" for m in ms))
    assert suction[-1][1].position[0] == 1.0
    status, result = grip(client, 0.0)
    assert status == GoalStatus.STATUS_SUCCEEDED
    assert (result.position, result.reached_goal, result.stalled) == (0.0, True, False)


def test_a_crate_under_the_vacuum_is_held_and_released(cell) -> None:
    client, port = cell
    tip = changer_pose(np.zeros(6))[:3, 3] + (0.30, 0.0, 0.0)  # the suction zone, z-down
    with WorldControllerClient(port=port, timeout=10.0) as wc:
        wc.create("floating", "WCCrate", tuple(tip), scale=(0.4, 0.4, 0.4), physics="None")
        try:
            status, result = grip(client, 1.0)
            assert status == GoalStatus.STATUS_SUCCEEDED
            assert (result.reached_goal, result.stalled) == (True, True)  # held: stalled
            status, result = grip(client, 0.0)
            assert (status, result.reached_goal, result.stalled) == (
                GoalStatus.STATUS_SUCCEEDED, True, False)
        finally:
            wc.kill("floating")


@pytest.mark.parametrize("position", [math.nan, 1.5, -0.2, math.inf])
def test_a_malformed_goal_is_aborted_and_nothing_is_sent(cell, position: float) -> None:
    client, _ = cell
    status, result = grip(client, position)
    assert (status, result.reached_goal) == (GoalStatus.STATUS_ABORTED, False)
    assert {m.state for m in statuses(client, f"{GRIPPER}/status", EffectorStatus, 0.3)} == \
        {OPEN}


def test_the_command_topic_sets_and_a_pending_command_gates_the_next(cell) -> None:
    client, _ = cell
    pub = client.node.create_publisher(EffectorCommand, f"{GRIPPER}/command", 10)
    deadline = time.monotonic() + 5
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    pub.publish(EffectorCommand(state=7))  # anything but OPEN closes (the seed's rule)
    pub.publish(EffectorCommand(state=OPEN))  # ignored: the CLOSE is pending
    got = client.collect(EffectorStatus, f"{GRIPPER}/status", 3.0,
                         until=lambda ms: any(m.state == CLOSE for m in ms))
    assert got[-1][1].state == CLOSE
    assert {m.state for m in statuses(client, f"{GRIPPER}/status", EffectorStatus, 0.5)} == \
        {CLOSE}  # the OPEN was dropped by the gate
    pub.publish(EffectorCommand(state=OPEN))  # a status showed CLOSE: the gate is open
    got = client.collect(EffectorStatus, f"{GRIPPER}/status", 3.0,
                         until=lambda ms: any(m.state == OPEN for m in ms))
    assert got and got[-1][1].state == OPEN, [m.state for _, m in got]
    client.node.destroy_publisher(pub)


def test_zz_a_tool_changer_open_drops_the_tool_and_its_goals_are_refused(cell) -> None:
    client, _ = cell  # last in the module: the gripper stays on the floor
    pub = client.node.create_publisher(EffectorCommand, f"{CHANGER}/command", 10)
    deadline = time.monotonic() + 5
    while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    pub.publish(EffectorCommand(state=OPEN))
    got = client.collect(ToolchangerStatus, f"{CHANGER}/status", 3.0,
                         until=lambda ms: any(m.effector_status.state == OPEN for m in ms))
    last = got[-1][1]
    assert last.effector_status.state == OPEN
    assert last.tool_name == GRIPPER  # kept, as the seed's RosSim keeps it
    assert statuses(client, f"{GRIPPER}/status", EffectorStatus, 0.5) == []  # silent
    status, result = grip(client, 1.0)
    assert (status, result.reached_goal) == (GoalStatus.STATUS_ABORTED, False)
    joints = client.collect(JointState, "joint_states", 2.0, until=bool)
    assert joints, "the node lives on"
    client.node.destroy_publisher(pub)
