"""Planned motions: collision-free and within every limit at 1 kHz, on goal, typed failures."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.planning.recheck import assert_rechecked, blocked_pairs
from usar_arm.arm.cycle import tcp_offset
from usar_arm.control.motion import MotionOptions, plan_motion
from usar_arm.control.timing import blended, stop_at_waypoints
from usar_arm.control.trajectory import MotionLimits, Trajectory
from usar_arm.core.errors import (
    FileFormatError,
    GoalInCollisionError,
    IKError,
    InvalidInputError,
    LinBlockedError,
    NoPathError,
    OutOfLimitsError,
    StartInCollisionError,
)
from usar_arm.core.shapes import CylinderShape
from usar_arm.core.spatial import transform
from usar_arm.planning.ompl_adapter import OmplOptions, edge_configurations
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import Scene, SceneObject, Sphere
from usar_arm.planning.scene_file import load_scene

DOWN = np.diag([1.0, -1.0, -1.0])  # tool0 pointing down


def _problems(robot: Robot, scene: str, count: int, seed: int) -> list[tuple[np.ndarray, ...]]:
    """Start/goal pairs, free, whose straight joint-space segment is blocked (OMPL needed)."""
    return blocked_pairs(robot.collision_world(load_scene(scene)), robot, count, seed)


@pytest.mark.parametrize("scene", ["table", "shelf", "cage"])
@pytest.mark.parametrize("blend", [False, True])
def test_ptp_plans_around_obstacles_within_every_limit(kr60: Robot, scene: str,
                                                       blend: bool) -> None:
    world = kr60.collision_world(load_scene(scene))
    for a, b in _problems(kr60, scene, 3, seed=11 + blend):
        plan = plan_motion(kr60, world, a, goal=b, options=MotionOptions(blend=blend))
        assert_rechecked(kr60, world, plan)


def test_blending_is_never_slower_than_stopping_on_the_same_path(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("shelf"))
    limits = MotionLimits.from_chain(kr60.chain, 0.5)
    ratios = []
    # The test is about durations, not planning speed: a budget of 20 s (RRTConnect stops at
    # its first path) keeps a loaded machine from turning slow plans into skipped problems.
    options = MotionOptions(ompl=OmplOptions(time_limit=20.0))
    for a, b in _problems(kr60, "shelf", 8, seed=5):
        try:
            path = plan_motion(kr60, world, a, goal=b, options=options).waypoints
        except NoPathError:
            continue  # random pairs can lie in regions OMPL does not connect at all
        if len(path) < 3:
            continue
        stop = stop_at_waypoints(kr60.chain.joint_names, path, limits)
        blend = blended(kr60.chain.joint_names, path, limits, world.in_collision_many)
        ratios.append(blend.duration / stop.duration)
    assert len(ratios) >= 3
    assert max(ratios) <= 1.0 + 1e-9 and min(ratios) < 0.95


def _cup_at(robot: Robot, xyz: tuple[float, float, float]) -> np.ndarray:
    """tool0's pose putting the gripper's suction cup at ``xyz``, pointing down."""
    return transform(DOWN, xyz) @ np.linalg.inv(tcp_offset(robot))


def test_ptp_to_a_pose_reaches_it(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    target = _cup_at(kr60, (1.45, 0.50, 1.10))  # above the bin, the tower in between
    start = np.array(kr60.ik_solver().solve(_cup_at(kr60, (1.45, -0.45, 1.0))).best.q)
    plan = plan_motion(kr60, world, start, pose=target)
    assert_rechecked(kr60, world, plan)


def test_lin_follows_a_straight_line(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    above = _cup_at(kr60, (1.45, -0.45, 1.0))
    start = np.array(kr60.ik_solver().solve(above).best.q)
    down = _cup_at(kr60, (1.45, -0.45, 0.82))  # 2 cm above the part
    plan = plan_motion(kr60, world, start, pose=down, options=MotionOptions(motion="lin"))
    assert_rechecked(kr60, world, plan)
    tips = np.array([kr60.kinematics.frame_pose(q, "tool0")[:3, 3]
                     for q in plan.trajectory.q[:: 20]])
    off_line = np.linalg.norm(tips[:, :2] - above[:2, 3], axis=1)
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
        assert json.loads(out.read_text())["scene"] == "cage"  # (what view and render show)
    assert outs[0] == outs[1] and len(outs[0]) > 2


def test_a_trajectory_records_the_scene_it_was_planned_in(tmp_path: Path) -> None:
    from usar_arm import Arm

    arm = Arm.from_files(Path(__file__).resolve().parents[2] / "robots/generated/KR60.urdf")
    mine = tmp_path / "cell.yaml"
    mine.write_text("name: cell\nobjects:\n  - {name: post, box: [0.1, 0.1, 0.5], "
                    "xyz: [1.5, 1.5, 0.25]}\n")
    goal = np.array([0.3, -0.5, 0.5, 0.0, 0.5, 0.0])
    for scene, recorded in (("table", "table"), (mine, str(mine.resolve())),
                            (load_scene("table"), None), (None, None)):
        traj = arm.plan(joints=goal, scene=scene).trajectory
        assert traj.scene == recorded
        traj.save(tmp_path / "t.json")
        assert Trajectory.load(tmp_path / "t.json").scene == recorded
    doc = json.loads((tmp_path / "t.json").read_text())
    assert "scene" not in doc  # (none known: the file says nothing)
    doc["scene"] = 3
    (tmp_path / "t.json").write_text(json.dumps(doc))
    with pytest.raises(FileFormatError, match="expected a scene's name or path, got 3"):
        Trajectory.load(tmp_path / "t.json")


# ------------------------------------------------------------------ regressions (issue 8)


def test_a_pose_no_ik_solution_can_be_reached_for_is_a_no_path_error(kr60: Robot) -> None:
    # (raised AttributeError: NoPathError has time_limit_s, not time_limit)
    world = kr60.collision_world(load_scene("cage"))
    ik = kr60.ik_solver()
    for a, b in _problems(kr60, "cage", 20, seed=3):  # the first whose every solution needs OMPL
        pose = kr60.kinematics.frame_pose(b, "tool0")
        solutions = [s.q for s in ik.solve(pose, all_solutions=True).solutions]
        if all(world.in_collision_many(edge_configurations(a, q, 0.01)).any()
               for q in solutions):
            break
    else:
        raise AssertionError("no problem whose every IK solution is blocked on the straight line")
    with pytest.raises(NoPathError) as info:
        plan_motion(kr60, world, a, pose=kr60.kinematics.frame_pose(b, "tool0"),
                    options=MotionOptions(ompl=OmplOptions(time_limit=1e-7)))
    assert "IK solution(s) could be reached" in str(info.value)
    assert info.value.time_limit_s == 1e-7


@pytest.mark.parametrize("how", ["joints", "pose-ptp", "pose-lin"])
def test_a_motion_to_where_the_arm_is_holds_still_and_can_be_saved(kr60: Robot, how: str,
                                                                   tmp_path: Path) -> None:
    # (returned t = [0, 0]: zero rate, and a file Trajectory.load refused)
    world = kr60.collision_world(load_scene("table"))
    q = np.array([0.3, -1.2, 1.0, 0.2, 0.6, 0.1])
    pose = kr60.kinematics.frame_pose(q, "tool0")
    plan = (plan_motion(kr60, world, q, goal=q) if how == "joints" else
            plan_motion(kr60, world, q, pose=pose, options=MotionOptions(motion=how[5:])))
    traj = plan.trajectory
    assert np.all(np.diff(traj.t) > 0) and traj.rate >= 250
    assert_rechecked(kr60, world, plan, start=q)
    traj.save(tmp_path / "hold.json")
    assert np.allclose(Trajectory.load(tmp_path / "hold.json").q[-1], traj.q[-1])


@pytest.mark.parametrize("motion", ["ptp", "lin"])
def test_a_goal_pose_that_is_no_rigid_transform_is_invalid_input(kr60: Robot,
                                                                 motion: str) -> None:
    # (NaN: ValueError from LIN; 3x3: IndexError; a scaled rotation: "unreachable")
    world = kr60.collision_world(load_scene("empty"))
    q = np.array([0.3, -1.2, 1.0, 0.2, 0.6, 0.1])
    good = kr60.kinematics.frame_pose(q, "tool0")
    nan = good.copy()
    nan[0, 3] = np.nan
    scaled = good.copy()
    scaled[:3, :3] *= 1.5
    mirrored = good.copy()
    mirrored[:3, 0] *= -1
    for pose, words in ((nan, "NaN"), (good[:3], "4x4"), (scaled, "rotation"),
                        (mirrored, "det"), ([[1, 2], [3]], "numbers")):
        with pytest.raises(InvalidInputError, match=words):
            plan_motion(kr60, world, q, pose=pose, options=MotionOptions(motion=motion))


def _pin_grazing(robot: Robot, q: np.ndarray, link: str, depth: float) -> Scene:
    """A 5 mm sphere overlapping ``link``'s cylinder by ``depth`` m at ``q``, on the side of it
    that moves parallel to its surface when the first joint turns."""
    body = max(robot.chain.link(link).elements, key=lambda e: e.shape.radius)  # not the core
    assert isinstance(body.shape, CylinderShape)
    cyl = robot.chain.link_poses(q)[link] @ body.origin.matrix()
    axis, centre = cyl[:3, 2], cyl[:3, 3]
    moving = np.cross([0.0, 0.0, 1.0], centre)
    normal = np.cross(axis, moving)
    normal *= np.sign(normal[2]) / np.linalg.norm(normal)
    pin = centre + normal * (body.shape.radius + 0.005 - depth)
    return Scene("pin", (SceneObject("pin", Sphere(0.005), transform(pos=pin)),))


def test_a_path_never_clips_an_obstacle_between_the_planners_checks(kr60: Robot) -> None:
    # (a free-pair plan in the shelf grazed board_top by 1 mm between two checks 0.01 rad
    # apart: 1 of 8482 samples of the 1 kHz re-check collided)
    a = np.array([-0.15, -0.6, 0.3, 0.0, 0.4, 0.0])
    b = np.array([0.15, -0.6, 0.3, 0.0, 0.4, 0.0])
    halfway = np.array([-0.145, -0.6, 0.3, 0.0, 0.4, 0.0])  # between two 0.01-rad checks
    world = kr60.collision_world(_pin_grazing(kr60, halfway, "link_4", depth=0.0005))
    assert world.in_collision(halfway)
    assert not world.in_collision_many(edge_configurations(a, b, 0.01)).any()  # missed so
    levers = world.lever_arms()
    assert world.in_collision_many(edge_configurations(a, b, 0.01, levers, 0.005)).any()
    plan = plan_motion(kr60, world, a, goal=b,
                       options=MotionOptions(ompl=OmplOptions(planner="RRTConnect")))
    assert len(plan.waypoints) > 2, "the straight segment through the pin was kept"
    # OMPL's own path (the straight segment, free at its 0.01 rad checks) had its segment
    # replanned densely, not the whole path
    assert (plan.details["repaired"], plan.details["dense_replans"]) == (1, 0)
    # the compiled planner checks every edge that densely as it searches: nothing to repair
    compiled = plan_motion(kr60, world, a, goal=b)
    assert compiled.details["planner"] == "CompiledRRTConnect"
    assert (compiled.details["repaired"], compiled.details["dense_replans"]) == (0, 0)
    for found in (plan, compiled):
        for p, q in itertools.pairwise(found.waypoints):
            assert not world.in_collision_many(edge_configurations(p, q, 0.01, levers,
                                                                   0.001)).any()
        assert_rechecked(kr60, world, found, start=a)


def _rims(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Points on both end circles of every collision cylinder at ``q`` (world, m)."""
    poses = robot.chain.link_poses(q)
    out = []
    for lk in robot.chain.links:
        for e in lk.elements:
            assert isinstance(e.shape, CylinderShape)
            out += _rim(poses[lk.name] @ e.origin.matrix(), e.shape)
    return np.array(out)


def _rim(t: np.ndarray, g: CylinderShape) -> list[np.ndarray]:
    """Points on both end circles of a cylinder at pose ``t``."""
    return [t[:3, :3] @ (g.radius * np.cos(ang), g.radius * np.sin(ang), z) + t[:3, 3]
            for z in (-g.length / 2, g.length / 2)
            for ang in np.linspace(0, 2 * np.pi, 12, endpoint=False)]


def test_lever_arms_bound_how_far_any_point_of_the_robot_moves(kr60: Robot,
                                                               fanuc: Robot) -> None:
    rng = np.random.default_rng(4)
    for robot in (kr60, fanuc):
        levers = robot.collision_world().lever_arms()
        chain = robot.chain
        for _ in range(40):
            q = rng.uniform(chain.lower(), chain.upper())
            dq = rng.normal(size=chain.dof) * 0.01
            moved = np.linalg.norm(_rims(robot, q + dq) - _rims(robot, q), axis=1).max()
            assert moved <= levers @ np.abs(dq) + 1e-9
        assert levers[1] > 1.0  # (a bound that means something: the shoulder moves the tip)
