"""Planned motions: collision-free and within every limit at 1 kHz, on goal, typed failures."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from usar_arm.control.timing import blended, stop_at_waypoints
from usar_arm.control.trajectory import MotionLimits, Trajectory, check_limits
from usar_arm.errors import (
    FileFormatError,
    GoalInCollisionError,
    IKError,
    LinBlockedError,
    NoPathError,
    OutOfLimitsError,
    StartInCollisionError,
)
from usar_arm.motion import MotionOptions, MotionPlan, plan_motion
from usar_arm.planning.ompl_adapter import OmplOptions, edge_configurations
from usar_arm.planning.scene_file import load_scene
from usar_arm.robot import Robot
from usar_arm.spatial import rotation_distance, transform

DOWN = np.diag([1.0, -1.0, -1.0])  # tool0 pointing down


def _recheck(robot: Robot, world, plan: MotionPlan) -> None:  # type: ignore[no-untyped-def]
    """The continuous motion, re-evaluated at 1 kHz: no collision, every limit kept."""
    timed = plan.timed
    assert timed is not None
    t = np.arange(0.0, timed.duration, 0.001)
    q, qd, qdd = timed.evaluate(t)
    report = check_limits(t, q, qd, qdd, plan.trajectory.limits, robot.chain.joint_names)
    assert report.within(1e-6), report
    assert not np.any(world.in_collision_many(q)), "collision along the trajectory"
    assert plan.trajectory.rate >= 250
    assert np.allclose(plan.trajectory.q[-1], plan.goal, atol=1e-9)
    if plan.goal_pose is not None:
        final = robot.kinematics.frame_pose(plan.trajectory.q[-1], "tool0")
        assert np.linalg.norm(final[:3, 3] - plan.goal_pose[:3, 3]) < 1e-3
        assert rotation_distance(final[:3, :3], plan.goal_pose[:3, :3]) < 1e-3


def _problems(robot: Robot, scene: str, count: int, seed: int) -> list[tuple[np.ndarray, ...]]:
    """Start/goal pairs, free, whose straight joint-space segment is blocked (OMPL needed)."""
    world = robot.collision_world(load_scene(scene))
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        a, b = rng.uniform(robot.chain.lower(), robot.chain.upper(), size=(2, robot.chain.dof))
        if world.in_collision(a) or world.in_collision(b):
            continue
        if world.in_collision_many(edge_configurations(a, b, 0.01)).any():
            out.append((a, b))
    return out


@pytest.mark.parametrize("scene", ["table", "shelf", "cage"])
@pytest.mark.parametrize("blend", [False, True])
def test_ptp_plans_around_obstacles_within_every_limit(kr60: Robot, scene: str,
                                                       blend: bool) -> None:
    world = kr60.collision_world(load_scene(scene))
    for a, b in _problems(kr60, scene, 3, seed=11 + blend):
        plan = plan_motion(kr60, world, a, goal=b, options=MotionOptions(blend=blend))
        assert plan.details["planner"] == "RRTConnect"
        _recheck(kr60, world, plan)


def test_blending_is_never_slower_than_stopping_on_the_same_path(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("shelf"))
    limits = MotionLimits.from_chain(kr60.chain, 0.5)
    ratios = []
    for a, b in _problems(kr60, "shelf", 8, seed=5):
        try:
            path = plan_motion(kr60, world, a, goal=b).waypoints
        except NoPathError:
            continue  # random pairs can lie in regions OMPL does not connect within 2 s
        if len(path) < 3:
            continue
        stop = stop_at_waypoints(kr60.chain.joint_names, path, limits)
        blend = blended(kr60.chain.joint_names, path, limits, world.in_collision_many)
        ratios.append(blend.duration / stop.duration)
    assert len(ratios) >= 3
    assert max(ratios) <= 1.0 + 1e-9 and min(ratios) < 0.95


def test_ptp_to_a_pose_reaches_it(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    target = transform(DOWN, (1.45, 0.50, 1.10))  # above the bin, the tower in between
    start = np.array(kr60.ik_solver().solve(transform(DOWN, (1.45, -0.45, 1.0))).best.q)
    plan = plan_motion(kr60, world, start, pose=target)
    _recheck(kr60, world, plan)


def test_lin_follows_a_straight_line(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    above = transform(DOWN, (1.45, -0.45, 1.0))
    start = np.array(kr60.ik_solver().solve(above).best.q)
    down = transform(DOWN, (1.45, -0.45, 0.82))
    plan = plan_motion(kr60, world, start, pose=down, options=MotionOptions(motion="lin"))
    _recheck(kr60, world, plan)
    tips = np.array([kr60.kinematics.frame_pose(q, "tool0")[:3, 3]
                     for q in plan.trajectory.q[:: 20]])
    off_line = np.linalg.norm(tips[:, :2] - [1.45, -0.45], axis=1)
    assert off_line.max() < 1e-3  # the tool stays on the vertical line


def test_lin_into_an_obstacle_names_where_it_is_blocked(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    start = np.array(kr60.ik_solver().solve(transform(DOWN, (1.5, 0.0, 1.6))).best.q)
    with pytest.raises(LinBlockedError) as info:
        plan_motion(kr60, world, start, pose=transform(DOWN, (1.5, 0.0, 1.2)),
                    options=MotionOptions(motion="lin"))
    assert "tower" in info.value.reason
    assert 0.0 < info.value.fraction < 1.0
    assert info.value.point_m[2] > 1.2


def test_failures_are_typed_and_name_the_culprit(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    home = np.zeros(6)
    inside_table = np.array([0.0, -1.9, 1.3, 0.0, 0.6, 0.0])
    assert world.in_collision(inside_table)
    with pytest.raises(StartInCollisionError) as start_info:
        plan_motion(kr60, world, inside_table, goal=home)
    assert start_info.value.pairs
    with pytest.raises(GoalInCollisionError):
        plan_motion(kr60, world, home, goal=inside_table)
    with pytest.raises(OutOfLimitsError) as limits:
        plan_motion(kr60, world, home, goal=np.array([0, 1.0, 0, 0, 0, 0.0]))
    assert limits.value.joint == "joint_a2"
    with pytest.raises(IKError):
        plan_motion(kr60, world, home, pose=transform(pos=(4.0, 0.0, 1.0)))
    a, b = _problems(kr60, "cage", 1, seed=3)[0]
    with pytest.raises(NoPathError) as nopath:
        plan_motion(kr60, kr60.collision_world(load_scene("cage")), a, goal=b,
                    options=MotionOptions(ompl=OmplOptions(time_limit=1e-4)))
    assert "RRTConnect" in str(nopath.value) and "0.0001 s" in str(nopath.value)


def test_trajectories_round_trip_through_json(kr60: Robot, tmp_path: Path) -> None:
    world = kr60.collision_world(load_scene("empty"))
    plan = plan_motion(kr60, world, np.zeros(6), goal=np.array([0.5, -0.5, 0.5, 0.5, 0.5, 0.5]))
    path = tmp_path / "t.json"
    plan.trajectory.save(path)
    back = Trajectory.load(path)
    assert np.array_equal(back.q, plan.trajectory.q) and back.joint_names == kr60.chain.joint_names
    assert np.allclose(back.at(back.duration / 3)[0], plan.trajectory.at(back.duration / 3)[0])
    doc = json.loads(path.read_text())
    assert {"joint_names", "t", "q", "qd", "qdd", "waypoints", "limits"} <= set(doc)
    doc["q"] = doc["q"][:-1]
    path.write_text(json.dumps(doc))
    with pytest.raises(FileFormatError) as info:
        Trajectory.load(path)
    assert info.value.field == "q"


def test_plans_are_reproducible_with_a_seed(tmp_path: Path) -> None:
    outs = []
    for k in range(2):
        out = tmp_path / f"t{k}.json"
        subprocess.run([sys.executable, "-m", "usar_arm.cli.main", "plan", "--urdf",
                        str(Path(__file__).resolve().parents[2] / "robots/generated/KR60.urdf"),
                        "--joints", "1.2", "-1.0", "1.0", "0", "0.5", "0", "--from-joints",
                        "-1.2", "-1.0", "1.0", "0", "0.5", "0", "--scene", "cage", "--seed", "7",
                        "--out", str(out), "-q"], check=True, timeout=120)
        outs.append(json.loads(out.read_text())["waypoints"])
    assert outs[0] == outs[1] and len(outs[0]) > 2
