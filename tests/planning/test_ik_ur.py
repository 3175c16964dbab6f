"""The closed form of arms with three parallel axes (usar_arm.planning.ur, .ur_kernel) on the UR5
of example-robot-data and synthetic UR-type arms, judged by Pinocchio's forward kinematics of
the same URDF (which shares no code with the closed form)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.planning.ur_arms import NEAR, ODD, UR10, synthetic, ur5
from usar_arm.planning import ur_kernel
from usar_arm.planning.ik import IKOptions
from usar_arm.planning.opw import NotOrthoParallel, OrthoParallelArm
from usar_arm.planning.poe import PoeModel
from usar_arm.planning.robot import Robot
from usar_arm.planning.ur import NotThreeParallel, ThreeParallelArm

ARMS = ("ur5", "ur10", "odd")
GENERIC = np.array([0.4, -1.3, 1.1, -0.7, 1.2, 0.5])
"""A configuration whose pose all eight branches reach on every arm of ARMS."""


@pytest.fixture(scope="module")
def arms() -> dict[str, Robot]:
    return {"ur5": ur5(), "ur10": synthetic("ur10", UR10), "odd": synthetic("odd", ODD)}


def _form(robot: Robot) -> ThreeParallelArm:
    ik = robot.ik_solver()
    assert ik.branches is not None and ik.branches.ur is not None, ik.analytic_reason
    return ik.branches.ur


def _pose(robot: Robot, q: np.ndarray) -> np.ndarray:
    return robot.kinematics.frame_pose(np.asarray(q, float), robot.ik_solver().frame)


def _gap(a: np.ndarray, b: np.ndarray) -> float:
    """Largest pose difference: position (m) or rotation matrix entry."""
    return float(np.max(np.abs(a - b)))


def _turns(a: np.ndarray | list[float], b: np.ndarray | list[float]) -> np.ndarray:
    """Joint differences (rad) up to whole turns."""
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


def _parts(target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.ascontiguousarray(target[:3, :3]), np.ascontiguousarray(target[:3, 3])


@pytest.mark.parametrize("name", ARMS)
@settings(max_examples=150, deadline=None)
@given(u=st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
def test_every_branch_reaches_the_pose_and_the_kernel_agrees(arms: dict[str, Robot], name: str,
                                                             u: list[float]) -> None:
    robot = arms[name]
    form = _form(robot)
    q = np.array(u) * math.pi
    target = _pose(robot, q)
    rot, pos = _parts(target)
    branches = form.solve(rot, pos, q6_free=q[5])
    # A wrist near its singularity with the elbow straight or folded (the pose on the edge of
    # the reach) may lose its branches to rounding: the Python path then searches numerically.
    doubly = abs(math.sin(q[2])) < 1e-3 and abs(math.sin(q[4])) < 1e-3
    assert branches or doubly, (name, list(q))
    # Within 1e-9 of the pose; within |sin q5| of the wrist singularity, q6 is taken as given
    # (ur.SINGULAR_WRIST) or known to eps / |sin q5| only, and the pose off by up to that
    # times pi (the branch with the other sign of q5 has the other q6).
    tol = 1e-9 + (4 * abs(math.sin(q[4])) if abs(math.sin(q[4])) < 1e-6 else 0.0)
    for b in branches:
        assert _gap(_pose(robot, np.array(b)), target) < tol, (name, list(q), b)
    # The generating configuration is one of them, unless the wrist is doubly near its
    # singularity; with the elbow straight or folded, the elbow's acos (near +-1) turns the
    # rounding into up to a micro-radian of q2, q3 (the pose does not move: within 1e-9 above).
    straight = abs(math.sin(q[2])) < 1e-3
    if branches and not doubly:
        nearest = min(float(np.max(_turns(b, q))) for b in branches)
        assert nearest < (1e-5 if straight else 1e-6), (name, list(q))
    out = np.empty((8, 6))
    count = ur_kernel.branches_free(rot, pos, ur_kernel.pack(form), float(q[5]), out)
    assert count == len(branches)
    assert np.allclose(out[:count], np.array(branches).reshape(-1, 6), atol=1e-12)


@pytest.mark.parametrize("name", ARMS)
def test_a_generic_pose_has_eight_distinct_branches(arms: dict[str, Robot], name: str) -> None:
    robot = arms[name]
    target = _pose(robot, GENERIC)
    branches = np.array(_form(robot).solve(*_parts(target)))
    assert len(branches) == 8
    for i, a in enumerate(branches):
        assert all(np.max(_turns(a, b)) > 1e-3 for b in branches[i + 1:])
    every = robot.ik_solver().solve(target, all_solutions=True)
    assert len(every.solutions) == 8 and every.method == "analytic-ur+newton"
    for sol in every.solutions:
        assert _gap(_pose(robot, sol.q), target) < 1e-5


@pytest.mark.parametrize("name", ARMS)
@pytest.mark.parametrize("q5", [0.0, 1e-12, 1e-8, 1e-5, math.pi, math.pi - 1e-9])
def test_a_singular_wrist_gives_a_finite_exact_answer(arms: dict[str, Robot], name: str,
                                                      q5: float) -> None:
    robot = arms[name]
    q = np.array([0.3, -1.0, 1.2, 0.4, q5, 0.7])
    target = _pose(robot, q)
    branches = _form(robot).solve(*_parts(target), q6_free=-0.4)
    assert branches and np.all(np.isfinite(branches))
    # Within |sin q5| of the singularity q6 is taken as given (-0.4, not 0.7): the rotation
    # is then off by at most |sin q5| times the error of q6 (Newton finishes).
    for b in branches:
        assert _gap(_pose(robot, np.array(b)), target) < 1e-9 + 4 * abs(math.sin(q5))
    seed = q + np.array([0.1, -0.1, 0.1, 0.2, 0.0, -0.3])
    sol = robot.ik_solver().solve(target, seed).best
    assert np.all(np.isfinite(sol.q)) and _gap(_pose(robot, sol.q), target) < 1e-5
    if q5 == 0.0:  # q6 is free (q2, q3, q4 follow it): it stays where the seed has it
        assert sol.q[5] == pytest.approx(seed[5], abs=1e-6)


def test_the_ur5_uses_the_closed_form_and_returns_the_branch_nearest_the_seed(
        arms: dict[str, Robot]) -> None:
    robot = arms["ur5"]
    ik = robot.ik_solver()
    assert ik.method == "analytic-ur" and ik.analytic is None  # (analytic: the OPW form)
    lo, hi = robot.chain.lower(), robot.chain.upper()
    rng = np.random.default_rng(4)
    for _ in range(150):
        q, seed = rng.uniform(lo, hi), rng.uniform(lo, hi)
        target = _pose(robot, q)
        best = ik.solve(target, seed)
        assert best.method == "analytic-ur+newton"
        assert _gap(_pose(robot, best.best.q), target) < 1e-5
        every = ik.solve(target, seed, all_solutions=True).solutions  # (windings near seed)
        assert 1 <= len(every) <= 8
        nearest = min(every, key=lambda s: float(np.sum((s.q - seed) ** 2)))
        assert np.max(np.abs(best.best.q - nearest.q)) < ik.options.distinct
        rot, pos = _parts(target)
        python, _, _ = ik._solve_analytic(rot, pos, seed, False, None)
        assert np.max(np.abs(best.best.q - python[0].q)) < ik.options.distinct


def test_the_batch_solver_uses_the_closed_form_too(arms: dict[str, Robot]) -> None:
    robot = arms["odd"]
    lo, hi = robot.chain.lower(), robot.chain.upper()
    qs = np.random.default_rng(6).uniform(lo, hi, size=(300, 6))
    targets = np.array([_pose(robot, q) for q in qs])
    batch = robot.ik_solver().solve_batch(targets, (lo + hi) / 2)
    assert batch.success.all()
    for i in range(0, 300, 10):
        assert _gap(_pose(robot, batch.q[i]), targets[i]) < 1e-5


def test_an_ortho_parallel_arm_is_refused_with_the_reason(kr60: Robot) -> None:
    poe = PoeModel(kr60.chain)
    tool = kr60.chain.frame_pose(kr60.ik_solver().frame, np.zeros(6))
    with pytest.raises(NotThreeParallel, match=r"joint 3 parallel to joint 4: off by 1.0"):
        ThreeParallelArm(poe.axes, poe.points, tool)
    assert kr60.ik_solver().method == "analytic"  # still the OPW form


def test_an_arm_outside_both_classes_says_why(arms: dict[str, Robot]) -> None:
    robot = arms["ur5"]
    poe = PoeModel(robot.chain)
    tool = robot.chain.frame_pose(robot.ik_solver().frame, np.zeros(6))
    with pytest.raises(NotOrthoParallel, match="joint 3 perpendicular to joint 4"):
        OrthoParallelArm(poe.axes, poe.points, tool)
    tilted = poe.axes.copy()
    tilted[4] = np.array([0.0, math.sin(0.1), -math.cos(0.1)])  # joint 5 leans 0.1 rad
    with pytest.raises(NotThreeParallel, match=r"joint 4 perpendicular to joint 5: off by 0.0998"):
        ThreeParallelArm(tilted, poe.points, tool)
    apart = poe.points.copy()
    apart[5] += np.array([0.2, 0.0, 0.0])  # axis 6 moved 0.2 m off axis 5
    with pytest.raises(NotThreeParallel, match=r"axes 5 and 6 miss each other by 0.2000 m"):
        ThreeParallelArm(poe.axes, apart, tool)


def test_without_the_closed_form_the_ur5_is_solved_numerically(arms: dict[str, Robot]) -> None:
    ik = arms["ur5"].ik_solver(IKOptions(use_analytic=False))
    assert ik.method == "numeric"
    target = _pose(arms["ur5"], GENERIC)
    assert _gap(_pose(arms["ur5"], ik.solve(target, GENERIC + 0.05).best.q), target) < 1e-5


def test_an_arm_slightly_off_the_class_is_solved_by_the_closed_form_and_newton() -> None:
    robot = synthetic("near", NEAR)
    ik = robot.ik_solver()
    assert ik.method == "analytic-ur"
    lo, hi = robot.chain.lower(), robot.chain.upper()
    rng = np.random.default_rng(12)
    methods: dict[str, int] = {}
    for _ in range(300):
        q, seed = rng.uniform(lo, hi), rng.uniform(lo, hi)
        target = _pose(robot, q)
        result = ik.solve(target, seed)
        methods[result.method] = methods.get(result.method, 0) + 1
        assert _gap(_pose(robot, result.best.q), target) < 1e-5
        assert np.all(result.best.q >= lo - 1e-9) and np.all(result.best.q <= hi + 1e-9)
    assert methods.get("analytic-ur+newton", 0) >= 295, methods
