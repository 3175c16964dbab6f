"""Every IK solution of a batch of poses: each one reaches its pose inside the limits (checked
by Pinocchio on the URDF), none is missed where the closed form applies, and the
manipulability and margin are what their definitions say (Pinocchio's Jacobian)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.planning.ik import IKOptions
from usar_arm.planning.robot import Robot
from usar_arm.workspace.solver import AllSolutions


def _poses(robot: Robot, qs: np.ndarray) -> np.ndarray:
    return np.array([robot.kinematics.frame_pose(q, "tool0") for q in qs])


def _yoshikawa(robot: Robot, q: np.ndarray) -> float:
    jac = robot.kinematics.jacobian(q, "tool0")
    return float(np.sqrt(max(np.linalg.det(jac @ jac.T), 0.0)))


@given(st.integers(0, 2**31 - 1))
@settings(max_examples=15, deadline=None)
def test_kr60_every_solution_reaches_its_pose_and_the_configuration_it_came_from_is_among_them(
        kr60: Robot, seed: int) -> None:
    rng = np.random.default_rng(seed)
    chain = kr60.chain
    qs = rng.uniform(chain.lower() * 0.95, chain.upper() * 0.95, size=(40, chain.dof))
    sigma = np.array([np.linalg.svd(kr60.kinematics.jacobian(q, "tool0"), compute_uv=False)[-1]
                      for q in qs])
    qs = qs[sigma > 0.05]  # away from singularities, where nearby solutions merge
    solver = AllSolutions(chain, kr60.ik_solver())
    assert solver.method == "analytic"
    targets = _poses(kr60, qs)
    c = solver.solve(targets[:, :3, :3], targets[:, :3, 3])
    for k, q in enumerate(qs):
        found = c.q[k, :c.count[k]]
        assert np.min(np.max(np.abs(found - q), axis=1)) < 1e-3, "the source was missed"
        for s, m, d in zip(found, c.manipulability[k], c.margin[k], strict=False):
            reached = kr60.kinematics.frame_pose(s, "tool0")
            assert np.linalg.norm(reached[:3, 3] - targets[k, :3, 3]) < 2e-5
            assert np.all(s >= chain.lower()) and np.all(s <= chain.upper())
            assert np.isclose(m, _yoshikawa(kr60, s), rtol=1e-6, atol=1e-9)
            assert np.isclose(d, min(np.min(s - chain.lower()), np.min(chain.upper() - s)))


def test_the_closed_form_finds_what_the_ik_solver_finds_with_every_branch(kr60: Robot) -> None:
    rng = np.random.default_rng(3)
    chain = kr60.chain
    qs = rng.uniform(chain.lower(), chain.upper(), size=(60, chain.dof))
    targets = _poses(kr60, qs)
    c = AllSolutions(chain, kr60.ik_solver()).solve(targets[:, :3, :3], targets[:, :3, 3])
    ik = kr60.ik_solver()
    for k, t in enumerate(targets):
        reference = ik.solve(t, all_solutions=True).solutions
        ours = c.q[k, :c.count[k]]
        for sol in reference:
            if abs(np.sin(sol.q[4])) < 0.05:
                continue  # at the wrist singularity the split of q4 + q6 is arbitrary
            assert np.min(np.max(np.abs(ours - sol.q), axis=1)) < 1e-3


def test_unreachable_poses_have_no_solution(kr60: Robot) -> None:
    solver = AllSolutions(kr60.chain, kr60.ik_solver())
    far = np.array([[5.0, 0.0, 1.0], [0.0, -4.0, 0.0], [0.0, 0.0, 6.0]])
    c = solver.solve(np.broadcast_to(np.eye(3), (3, 3, 3)), far)
    assert np.all(c.count == 0)


def test_any_arm_gets_numeric_solutions_that_reach_their_pose(fanuc: Robot) -> None:
    solver = AllSolutions(fanuc.chain, fanuc.ik_solver())
    assert solver.method == "numeric"
    rng = np.random.default_rng(4)
    chain = fanuc.chain
    qs = rng.uniform(chain.lower(), chain.upper(), size=(30, chain.dof))
    targets = _poses(fanuc, qs)
    c = solver.solve(targets[:, :3, :3], targets[:, :3, 3])
    assert (c.count > 0).mean() > 0.8
    for k in range(len(qs)):
        for s in c.q[k, :c.count[k]]:
            reached = fanuc.kinematics.frame_pose(s, "tool0")
            assert np.linalg.norm(reached[:3, 3] - targets[k, :3, 3]) < 2e-5
            assert np.all(s >= chain.lower() - 1e-12) and np.all(s <= chain.upper() + 1e-12)


def test_solutions_are_distinct(kr60: Robot) -> None:
    solver = AllSolutions(kr60.chain, kr60.ik_solver(IKOptions()))
    rng = np.random.default_rng(5)
    qs = rng.uniform(kr60.chain.lower(), kr60.chain.upper(), size=(100, 6))
    t = _poses(kr60, qs)
    c = solver.solve(t[:, :3, :3], t[:, :3, 3])
    for k in range(len(qs)):
        s = c.q[k, :c.count[k]]
        for i in range(len(s)):
            for j in range(i):
                assert np.max(np.abs(s[i] - s[j])) >= 1e-3
