"""Inverse kinematics: it reaches the target, never misses, and says why when it cannot."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.core.errors import AllSolutionsInCollisionError, JointLimitError, UnreachableError
from usar_arm.core.spatial import rotation_distance, transform
from usar_arm.planning.ik import IKOptions
from usar_arm.planning.poe import PoeModel
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene_file import load_scene


def _reached(robot: Robot, q: np.ndarray, target: np.ndarray, tol: float = 1e-5) -> bool:
    pose = robot.kinematics.frame_pose(q, "tool0")
    return (np.linalg.norm(pose[:3, 3] - target[:3, 3]) < tol
            and rotation_distance(pose[:3, :3], target[:3, :3]) < tol)


def _inside(robot: Robot, q: np.ndarray) -> bool:
    return bool(np.all(q >= robot.chain.lower() - 1e-9) and np.all(q <= robot.chain.upper()
                                                                    + 1e-9))


def test_the_kr60_uses_the_closed_form_with_parameters_from_its_own_axes(kr60: Robot) -> None:
    ik = kr60.ik_solver()
    assert ik.method == "analytic"
    p = ik.analytic.parameters()  # type: ignore[union-attr]
    # The USARSim KR60 (docs/protocol.md section 7): shoulder 0.796 m high and 0.424 m forward,
    # upper arm ~1.004 m, forearm 0.983 m, wrist centre 0.169 m above the elbow; its wrist axes
    # miss each other by about a millimetre.
    assert p.c1 == pytest.approx(0.796, abs=1e-6) and p.a1 == pytest.approx(0.424, abs=1e-6)
    assert p.c2 == pytest.approx(1.004, abs=1e-3) and p.c3 == pytest.approx(0.983, abs=1e-6)
    assert p.a2 == pytest.approx(-0.169, abs=1e-6)
    assert 0 < p.wrist_offset < 0.005


def test_the_second_arm_uses_the_numeric_solver(fanuc: Robot) -> None:
    ik = fanuc.ik_solver()
    assert ik.method == "numeric" and "6 revolute" in ik.analytic_reason


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_kr60_every_solution_reaches_the_pose_inside_the_limits(kr60: Robot,
                                                                data: st.DataObject) -> None:
    # At least 1 mrad inside the limits: a pose whose only solutions lie exactly on a limit
    # *and* at the wrist singularity is the one case the polish can miss (see the note).
    lo, hi = kr60.chain.lower() + 1e-3, kr60.chain.upper() - 1e-3
    q = np.array([data.draw(st.floats(float(a), float(b))) for a, b in zip(lo, hi, strict=True)])
    target = kr60.kinematics.frame_pose(q, "tool0")
    result = kr60.ik_solver().solve(target, all_solutions=True)
    assert result.solutions
    for sol in result.solutions:
        assert _reached(kr60, np.array(sol.q), target) and _inside(kr60, np.array(sol.q))
    qs = [np.array(s.q) for s in result.solutions]
    for i, a in enumerate(qs):  # distinct
        assert all(np.max(np.abs(a - b)) > 1e-3 for b in qs[i + 1:])
    # The generating configuration is among them, up to the polishing tolerance, unless the
    # wrist is nearly singular, where nearby configurations reach the same pose, or the elbow
    # nearly straight, where the two elbow branches of the closed form lie within a few
    # hundredths of a radian and the polish can take both to the same exact solution
    # (q = (0, 0, 1.4375, 0, 1, 1) gave (0, 0.033, 1.372, 0, 0.967, 1) for both).
    arms = kr60.ik_solver().analytic.arm_branches(target[:3, :3], target[:3, 3])  # type: ignore
    elbow_straight = any(abs(a[0] - b[0]) < 1e-9 and abs(a[2] - b[2]) < 0.2
                         for i, a in enumerate(arms) for b in arms[i + 1:])
    if abs(math.sin(q[4])) > 0.01 and not elbow_straight:
        assert min(np.max(np.abs(a - q)) for a in qs) < 1e-3 + _spread(kr60, q)


def _spread(robot: Robot, q: np.ndarray, tol: float = 1e-5) -> float:
    """How far (rad) from ``q`` a configuration can lie that reaches q's tool0 pose within the
    solver's tolerance (``tol`` m and rad): ``tol`` over the Jacobian's smallest singular value,
    twice (both tolerances at once, and the linearisation). About 1e-4 rad for most
    configurations; near a singularity the solutions polished to ``tol`` spread that far."""
    sigma = np.linalg.svd(robot.kinematics.jacobian(q, "tool0"), compute_uv=False)[-1]
    return 2.0 * tol / float(sigma)


def test_near_the_shoulder_singularity_a_solution_lies_within_the_spread(kr60: Robot) -> None:
    # A campaign run's counterexample to the 1 mrad rule above: the wrist centre almost on axis
    # 1, smallest singular value 4.5e-5, the solution found 23 mrad from q, reaching the pose.
    q = np.array([0.0, -0.296875, 2.5, 2.0, 0.125, 0.0])
    target = kr60.kinematics.frame_pose(q, "tool0")
    qs = [np.array(s.q) for s in kr60.ik_solver().solve(target, all_solutions=True).solutions]
    assert all(_reached(kr60, a, target) for a in qs)
    assert _spread(kr60, q) > 0.1  # the premise: this configuration is that singular
    assert min(np.max(np.abs(a - q)) for a in qs) < 1e-3 + _spread(kr60, q)


def test_a_solution_exactly_on_a_joint_limit_is_found(kr60: Robot) -> None:
    q = np.array([0.0, 0.0, 2.757, -2.0, 1.0, 2.0])  # joint 3 on its upper limit
    target = kr60.kinematics.frame_pose(q, "tool0")
    every = kr60.ik_solver().solve(target, all_solutions=True).solutions
    assert min(np.max(np.abs(np.array(s.q) - q)) for s in every) < 1e-6
    assert all(_inside(kr60, np.array(s.q)) for s in every)


def test_the_nearest_solution_is_the_one_nearest_the_seed(kr60: Robot) -> None:
    rng = np.random.default_rng(5)
    ik = kr60.ik_solver()
    for _ in range(100):
        q = rng.uniform(kr60.chain.lower(), kr60.chain.upper())
        seed = rng.uniform(kr60.chain.lower(), kr60.chain.upper())
        target = kr60.kinematics.frame_pose(q, "tool0")
        every = ik.solve(target, all_solutions=True).solutions
        best = ik.solve(target, seed).best
        nearest = min(every, key=lambda s: float(np.sum((np.array(s.q) - seed) ** 2)))
        # The same solution (the compiled path polishes by its own Newton steps, so the two
        # agree within the tolerance, not to the last bit): closer than `distinct` apart.
        assert np.max(np.abs(np.array(best.q) - nearest.q)) < ik.options.distinct


def test_the_batch_solver_agrees_with_single_queries_and_misses_nothing(kr60: Robot) -> None:
    rng = np.random.default_rng(9)
    qs = rng.uniform(kr60.chain.lower(), kr60.chain.upper(), size=(500, 6))
    targets = np.array([kr60.kinematics.frame_pose(q, "tool0") for q in qs])
    seeds = (kr60.chain.lower() + kr60.chain.upper()) / 2
    ik = kr60.ik_solver()
    batch = ik.solve_batch(targets, seeds)
    assert batch.success.all()
    for i in range(0, 500, 25):
        single = ik.solve(targets[i], seeds).best
        assert np.allclose(batch.q[i], single.q, atol=1e-4)
        assert _reached(kr60, batch.q[i], targets[i])


def test_the_numeric_solver_handles_a_prismatic_rail_and_wide_joints(fanuc: Robot) -> None:
    rng = np.random.default_rng(3)
    ik = fanuc.ik_solver()
    lo, hi = fanuc.chain.lower(), fanuc.chain.upper()
    for _ in range(40):
        q = rng.uniform(lo, hi)
        target = fanuc.kinematics.frame_pose(q, "tool0")
        sol = ik.solve(target, q + rng.normal(0, 0.05, size=q.size)).best
        assert _reached(fanuc, np.array(sol.q), target) and _inside(fanuc, np.array(sol.q))


def test_joints_wider_than_a_turn_take_the_winding_nearest_the_seed(fanuc: Robot) -> None:
    ik = fanuc.ik_solver()
    q = np.array([0.2, 0.3, 0.5, 0.4, 0.3, 0.8, 0.5])
    target = fanuc.kinematics.frame_pose(q, "tool0")
    for turn in (-1, 0, 1):
        seed = q.copy()
        seed[6] += turn * 2 * math.pi  # J6 ranges over +-7.854 rad
        sol = ik.solve(target, seed).best
        assert sol.q[6] == pytest.approx(q[6] + turn * 2 * math.pi, abs=1e-4)


def test_unreachable_poses_say_by_how_much(kr60: Robot) -> None:
    with pytest.raises(UnreachableError) as info:
        kr60.ik_solver().solve(transform(pos=(5.0, 0.0, 0.8)))
    assert 2.0 < info.value.distance_m < 3.0
    assert "out of reach by" in str(info.value)


def test_poses_that_need_a_joint_beyond_its_limit_name_it(kr60: Robot) -> None:
    # Joint 5 at 2.4 rad, 0.324 past its 2.076 limit; the other branches are further out.
    q = np.array([0.3, -0.3, 0.3, 0.5, 2.4, 0.3])
    target = kr60.kinematics.frame_pose(q, "tool0")
    with pytest.raises(JointLimitError) as info:
        kr60.ik_solver().solve(target)
    assert info.value.joint == "joint_a5"
    assert info.value.excess == pytest.approx(2.4 - 2.076, abs=2e-3)
    assert "joint_a5" in str(info.value) and "outside" in str(info.value)


def test_when_every_solution_collides_the_pairs_are_named(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    target = transform(np.diag([1.0, -1.0, -1.0]), (1.5, 0.0, 0.9))  # inside the tower
    with pytest.raises(AllSolutionsInCollisionError) as info:
        kr60.ik_solver().solve(target, all_solutions=True, collision=world)
    assert any("tower" in pair for pair in info.value.pairs)
    assert 1 <= info.value.n_solutions <= 8


def test_tolerances_are_options(kr60: Robot) -> None:
    """Near the stretched arm (a slow Newton polish) the tolerance decides where the search
    stops: the default's answer is within 1e-5, a loose solver accepts a less polished one
    (measured 0.48 mm / 0.36 mrad), so a solver that ignored its options would fail here."""
    q = np.array([0.3, -0.6, 1.5244, 0.5, 0.7, -0.2])  # joint_a3 at the arm's full stretch
    target = kr60.kinematics.frame_pose(q, "tool0")
    strict = kr60.ik_solver().solve(target).best
    assert strict.position_error <= 1e-5 and strict.orientation_error <= 1e-5
    loose = kr60.ik_solver(IKOptions(position_tolerance=1e-3, orientation_tolerance=1e-3))
    sol = loose.solve(target).best
    assert 1e-5 < max(sol.position_error, sol.orientation_error)
    assert sol.position_error <= 1e-3 and sol.orientation_error <= 1e-3


def test_vectorised_kinematics_match_pinocchio(kr60: Robot, fanuc: Robot) -> None:
    for robot in (kr60, fanuc):
        poe = PoeModel(robot.chain)
        qs = np.random.default_rng(1).uniform(robot.chain.lower(), robot.chain.upper(),
                                              size=(50, robot.chain.dof))
        poses, jac = poe.frame_jacobian(qs, "tool0")
        for q, pose, j in zip(qs, poses, jac, strict=True):
            assert np.allclose(pose, robot.kinematics.frame_pose(q, "tool0"), atol=1e-8)
            assert np.allclose(j, robot.kinematics.jacobian(q, "tool0"), atol=1e-8)
