"""The goal rules of usar_arm.ros.goals as plain functions (no ROS needed): what is refused,
with which code, and the trajectory built from what is accepted."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from usar_arm import Arm
from usar_arm.core.model import JointType
from usar_arm.core.spatial import rpy_to_matrix
from usar_arm.ros.frames import TransformTree, quaternion
from usar_arm.ros.goals import (
    INVALID_GOAL,
    INVALID_JOINTS,
    OLD_HEADER_TIMESTAMP,
    GoalRejected,
    TrajectoryGoal,
    check_goal,
)

ROOT = Path(__file__).resolve().parents[2]
CHAIN = Arm.from_files(ROOT / "robots/generated/KR60.urdf").robot.chain
NAMES = CHAIN.joint_names
HERE = np.array([0.1, -0.5, 0.4, 0.0, 0.3, 0.0])


def goal(points: list[tuple[float, list[float]]], names: tuple[str, ...] = NAMES,
         **kw: object) -> TrajectoryGoal:
    return TrajectoryGoal(names, tuple(t for t, _ in points),
                          tuple(tuple(q) for _, q in points), **kw)  # type: ignore[arg-type]


def refused(g: TrajectoryGoal, now: float = 1000.0) -> GoalRejected:
    with pytest.raises(GoalRejected) as info:
        check_goal(g, CHAIN, HERE, now)
    return info.value


def test_a_goal_starts_where_the_arm_is_and_ends_at_its_last_point() -> None:
    target = HERE + 0.2
    checked = check_goal(goal([(2.0, target.tolist())]), CHAIN, HERE, 1000.0)
    trajectory = checked.trajectory
    assert np.allclose(trajectory.q[0], HERE) and np.allclose(trajectory.q[-1], target)
    assert trajectory.duration == pytest.approx(2.0)
    assert np.allclose(np.diff(trajectory.t), trajectory.t[1])  # a uniform grid
    assert np.all(np.isinf(checked.path_tolerance)) and checked.start_delay == 0


def test_the_joint_order_of_a_goal_is_its_own() -> None:
    order = [5, 4, 3, 2, 1, 0]
    target = HERE + np.arange(6) * 0.05
    g = goal([(2.0, target[order].tolist())], tuple(NAMES[i] for i in order))
    assert np.allclose(check_goal(g, CHAIN, HERE, 0.0).trajectory.q[-1], target)


def test_tolerances_zero_means_default_negative_means_none() -> None:
    g = goal([(2.0, HERE.tolist())], path_tolerance={"joint_a1": 0.01, "joint_a2": -1.0,
                                                     "joint_a3": 0.0})
    tol = check_goal(g, CHAIN, HERE, 0.0, default_tolerances=(0.5, 0.5)).path_tolerance
    assert tol[:4].tolist() == [0.01, math.inf, 0.5, 0.5]


@pytest.mark.parametrize(("g", "code", "words"), [
    (goal([(1.0, HERE.tolist())], ("joint_a1",) * 6), INVALID_JOINTS, "repeated"),
    (goal([(1.0, HERE.tolist()[:5])], NAMES[:5]), INVALID_JOINTS, "missing ['joint_a6']"),
    (goal([]), INVALID_GOAL, "no points"),
    (goal([(1.0, [math.nan] * 6)]), INVALID_GOAL, "finite"),
    (goal([(1.0, HERE.tolist()), (1.0, HERE.tolist())]), INVALID_GOAL, "strictly increasing"),
    (goal([(-1.0, HERE.tolist())]), INVALID_GOAL, "non-negative"),
    (goal([(1e6, HERE.tolist())]), INVALID_GOAL, "at most 600 s"),
    (goal([(1.0, HERE.tolist())], stamp=1e7), INVALID_GOAL, "in the future"),
    (goal([(1.0, [0, 0, 0, 0, 2.5, 0])]), INVALID_GOAL, "joint_a5 at 2.5000, outside"),
    (goal([(0.1, (HERE + 1.0).tolist())]), INVALID_GOAL, "above its velocity limit"),
    (goal([(0.0, (HERE + 0.2).tolist())]), INVALID_GOAL, "but the arm is at"),
    (goal([(1.0, HERE.tolist())], stamp=10.0), OLD_HEADER_TIMESTAMP, "ago"),
    (goal([(1.0, HERE.tolist())], accelerations=((0.0,),)), INVALID_GOAL, "6 accelerations"),
])
def test_a_goal_breaking_a_rule_is_refused_with_its_code(g: TrajectoryGoal, code: int,
                                                         words: str) -> None:
    error = refused(g)
    assert error.code == code and words in error.message, error.message


def test_a_stamp_in_the_future_delays_the_start() -> None:
    checked = check_goal(goal([(1.0, HERE.tolist())], stamp=1002.5), CHAIN, HERE, 1000.0)
    assert checked.start_delay == pytest.approx(2.5)


def test_the_tree_has_an_edge_per_joint_and_composes_to_forward_kinematics() -> None:
    tree = TransformTree(CHAIN)
    q = np.array([0.3, -1.0, 1.2, 0.5, -0.7, 2.0])
    edges = {e.child: e for e in tree.static_edges(np.eye(4)) + tree.moving_edges(q)}
    assert len(edges) == len(CHAIN.joints) + 1
    assert sum(j.type is not JointType.FIXED for j in CHAIN.joints) == len(tree.moving_edges(q))
    pose, frame = np.eye(4), "tool0"
    while frame != "world":
        pose, frame = edges[frame].matrix @ pose, edges[frame].parent
    assert np.allclose(pose, CHAIN.frame_pose("tool0", q), atol=1e-12)


@pytest.mark.parametrize("rpy", [(0, 0, 0), (np.pi, 0, 0), (0, np.pi, 0), (0, 0, np.pi),
                                 (0.3, -1.2, 2.9), (np.pi, 0.2, -np.pi / 2)])
def test_quaternions_are_unit_and_give_back_the_rotation(rpy: tuple[float, ...]) -> None:
    r = rpy_to_matrix(rpy)
    x, y, z, w = quaternion(r)
    assert math.isclose(x * x + y * y + z * z + w * w, 1.0) and w >= 0
    back = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    assert np.allclose(back, r, atol=1e-12)
