"""FollowJointTrajectory on `usar-arm ros`, sent by a real rclpy action client from this
process: joint_trajectory_controller's checks and error codes, tolerances, pre-emption and
cancel, each goal starting from where the previous one left the arm."""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed: pip install "
                                    "'usar-arm[ros]'")

from action_msgs.msg import GoalStatus
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from tests.ros.helpers import Client, NodeProcess, domain_id, make_goal

ACTION = "KR60Arm_controller/follow_joint_trajectory"
NAMES = [f"joint_a{i}" for i in range(1, 7)]
SUCCESSFUL, INVALID_GOAL, INVALID_JOINTS, OLD_HEADER_TIMESTAMP = 0, -1, -2, -3
PATH_TOLERANCE_VIOLATED, GOAL_TOLERANCE_VIOLATED = -4, -5


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Client]:
    folder = tmp_path_factory.mktemp("ros-goals")
    domain = domain_id()
    node = NodeProcess(domain, ["-v"], folder / "node.log")
    client = Client(domain)
    try:
        client.description()
        yield client
    finally:
        client.close()
        code = node.stop()
        assert code == 0, node.text()[-3000:]


def joints(client: Client) -> np.ndarray:
    got = client.collect(JointState, "joint_states", 5.0, until=bool)
    assert got, "no joint state"
    return np.array(got[-1][1].position)


def run(client: Client, goal: object) -> tuple[int, int, str]:
    handle = client.send(ACTION, goal)
    assert handle.accepted
    status, result = client.result(handle)
    return status, result.error_code, result.error_string


def moved(client: Client, before: np.ndarray) -> float:
    return float(np.max(np.abs(joints(client) - before)))


def test_a_goal_is_reached_with_feedback(client: Client) -> None:
    q0 = joints(client)
    q1 = q0 + np.array([0.3, -0.2, 0.2, 0.3, -0.3, 0.4])
    client.feedbacks.clear()
    started = time.perf_counter()
    handle = client.send(ACTION, make_goal(NAMES, [(1.0, (q0 + q1) / 2), (2.5, q1)],
                                           goal_tolerance=dict.fromkeys(NAMES, 0.002)))
    accepted_after = time.perf_counter() - started
    status, result = client.result(handle)
    assert (status, result.error_code) == (GoalStatus.STATUS_SUCCEEDED, SUCCESSFUL), \
        result.error_string
    # A sanity bound (the 20 ms target is the ros benchmark stage's, on an idle machine).
    assert accepted_after < 1.0, f"accepted after {accepted_after:.3f} s"
    assert np.max(np.abs(joints(client) - q1)) < 0.002
    # One per ASTA: 25 in 2.5 s at 10 Hz, fewer when a loaded simulator runs slow.
    assert len(client.feedbacks) >= 10, f"{len(client.feedbacks)} feedback messages"
    fb = client.feedbacks[len(client.feedbacks) // 2]
    assert list(fb.joint_names) == NAMES
    assert np.allclose(np.array(fb.error.positions),
                       np.array(fb.desired.positions) - np.array(fb.actual.positions))


@pytest.mark.parametrize(("change", "code", "words"), [
    ("unknown joint", INVALID_JOINTS, "unknown ['joint_x']"),
    ("missing joint", INVALID_JOINTS, "missing ['joint_a6']"),
    ("no points", INVALID_GOAL, "no points"),
    ("beyond a limit", INVALID_GOAL, "outside its limits"),
    ("too fast", INVALID_GOAL, "above its velocity limit"),
    ("times not increasing", INVALID_GOAL, "strictly increasing"),
    ("starts far from the arm", INVALID_GOAL, "but the arm is at"),
    ("old header stamp", OLD_HEADER_TIMESTAMP, "ago"),
    ("wrong sizes", INVALID_GOAL, "every point needs 6 positions"),
])
def test_a_bad_goal_is_refused_before_anything_moves(client: Client, change: str, code: int,
                                                     words: str) -> None:
    q0 = joints(client)
    names, points, stamp = list(NAMES), [(2.0, q0 + 0.1)], (0, 0)
    if change == "unknown joint":
        names[2] = "joint_x"
    elif change == "missing joint":
        names, points = names[:5], [(2.0, (q0 + 0.1)[:5])]
    elif change == "no points":
        points = []
    elif change == "beyond a limit":
        points = [(2.0, q0 + np.array([0, 0, 0, 0, 3.0, 0]))]
    elif change == "too fast":
        points = [(0.05, q0 + 0.5)]
    elif change == "times not increasing":
        points = [(2.0, q0 + 0.1), (1.0, q0 + 0.2)]
    elif change == "starts far from the arm":
        points = [(0.0, q0 + np.array([0.5, 0, 0, 0, 0, 0])), (2.0, q0)]
    elif change == "old header stamp":
        stamp = (int(time.time()) - 100, 0)
    elif change == "wrong sizes":
        points = [(2.0, [*(q0 + 0.1).tolist(), 0.0])]
    status, error_code, message = run(client, make_goal(names, points, stamp=stamp))
    assert (status, error_code) == (GoalStatus.STATUS_ABORTED, code), message
    assert words in message
    assert moved(client, q0) < 0.002


def test_a_path_tolerance_that_is_left_aborts_and_the_arm_holds(client: Client) -> None:
    q0 = joints(client)
    goal = make_goal(NAMES, [(3.0, q0 + np.array([0.6, 0, 0, 0, 0, 0]))],
                     path_tolerance={"joint_a1": 1e-5})
    status, code, message = run(client, goal)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, PATH_TOLERANCE_VIOLATED), message
    assert "joint_a1" in message and "path tolerance" in message
    time.sleep(1.0)  # the drives' lag: it comes to rest
    held = joints(client)
    time.sleep(0.5)
    assert moved(client, held) < 0.001, "the arm holds after the abort"
    assert abs(held[0] - q0[0]) < 0.3, "stopped early, not at the goal"


def test_a_goal_tolerance_that_is_not_met_is_reported(client: Client) -> None:
    q0 = joints(client)
    target = q0 + np.array([0, 0.123456789, 0, 0, 0, 0])  # between the ASTA's 1e-4 steps
    status, code, message = run(client, make_goal(NAMES, [(1.5, target)],
                                                  goal_tolerance={"joint_a2": 1e-9}))
    assert (status, code) == (GoalStatus.STATUS_ABORTED, GOAL_TOLERANCE_VIOLATED), message
    assert "joint_a2" in message and "goal tolerance" in message


def test_a_newer_goal_pre_empts_the_running_one(client: Client) -> None:
    q0 = joints(client)
    first = client.send(ACTION, make_goal(NAMES, [(6.0, q0 + np.array([0.8, 0, 0, 0, 0, 0]))]))
    time.sleep(1.5)
    mid = joints(client)
    q_second = q0 + np.array([0, 0.2, 0, 0, 0, 0])
    second = client.send(ACTION, make_goal(NAMES, [(2.5, q_second)]))
    status1, result1 = client.result(first)
    status2, result2 = client.result(second)
    assert status1 == GoalStatus.STATUS_ABORTED and "pre-empted" in result1.error_string
    assert (status2, result2.error_code) == (GoalStatus.STATUS_SUCCEEDED, SUCCESSFUL), \
        result2.error_string
    assert 0.05 < mid[0] - q0[0] < 0.7, "the first goal was under way"
    assert np.max(np.abs(joints(client) - q_second)) < 0.002


def test_of_goals_sent_back_to_back_the_newest_runs(client: Client) -> None:
    q0 = joints(client)
    first = client.send(ACTION, make_goal(NAMES, [(4.0, q0 + np.array([0.4, 0, 0, 0, 0, 0]))]))
    time.sleep(1.0)
    second = client.send(ACTION, make_goal(NAMES, [(3.0, q0 + np.array([0, 0, 0.3, 0, 0, 0]))]))
    third = client.send(ACTION, make_goal(NAMES, [(2.0, q0)]))
    outcomes = [client.result(h) for h in (first, second, third)]
    assert [s for s, _ in outcomes] == [GoalStatus.STATUS_ABORTED, GoalStatus.STATUS_ABORTED,
                                       GoalStatus.STATUS_SUCCEEDED], outcomes
    assert all("pre-empted" in r.error_string for _, r in outcomes[:2])
    assert np.max(np.abs(joints(client) - q0)) < 0.002


def test_a_cancelled_goal_stops_and_the_arm_holds(client: Client) -> None:
    q0 = joints(client)
    handle = client.send(ACTION, make_goal(NAMES, [(5.0, q0 + np.array([0, 0, 0, 0.8, 0, 0]))]))
    time.sleep(1.5)
    client.cancel(handle)
    status, result = client.result(handle)
    assert status == GoalStatus.STATUS_CANCELED, result.error_string
    time.sleep(1.0)  # the drives' lag: it comes to rest
    held = joints(client)
    assert 0.02 < held[3] - q0[3] < 0.7, "stopped on the way"
    time.sleep(0.5)
    assert moved(client, held) < 0.001, "and holds there"


def test_an_empty_joint_trajectory_message_stops_the_running_goal(client: Client) -> None:
    q0 = joints(client)
    handle = client.send(ACTION, make_goal(NAMES, [(4.0, q0 + np.array([0, 0, 0, 0, 0.5, 0]))]))
    publisher = client.node.create_publisher(JointTrajectory,
                                             "KR60Arm_controller/joint_trajectory", 10)
    deadline = time.monotonic() + 10
    while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(1.0)
    publisher.publish(JointTrajectory(joint_names=NAMES))
    status, result = client.result(handle)
    assert status == GoalStatus.STATUS_ABORTED and "empty" in result.error_string, \
        result.error_string
    client.node.destroy_publisher(publisher)


def test_the_joint_trajectory_topic_moves_the_arm(client: Client) -> None:
    q0 = joints(client)
    publisher = client.node.create_publisher(JointTrajectory,
                                             "KR60Arm_controller/joint_trajectory", 10)
    target = q0 + np.array([0, 0, 0, 0, 0, -0.3])
    msg = JointTrajectory(joint_names=NAMES)
    point = JointTrajectoryPoint(positions=target.tolist())
    point.time_from_start.sec = 2
    msg.points.append(point)
    deadline = time.monotonic() + 10
    while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    publisher.publish(msg)
    got = client.collect(JointState, "joint_states", 8.0,
                         until=lambda ms: bool(ms) and abs(ms[-1].position[5] - target[5])
                         < 0.002)
    assert abs(got[-1][1].position[5] - target[5]) < 0.002
