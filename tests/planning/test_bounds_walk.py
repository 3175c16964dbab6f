"""The compiled segment walk (usar_arm.planning.bounds_walk): the motion it bounds a body by at a
configuration holds over its horizon (judged by Pinocchio's poses, not the kernel's), it checks
coarse to fine, and it hands each undecided configuration to the exact judge as it comes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.planning import bounds, bounds_walk
from usar_arm.planning.bounds_arrays import MOVED, Packed, poses_into
from usar_arm.planning.robot import Robot, robot_from_files
from usar_arm.planning.scene import Box, Scene, SceneObject, Sphere

from ..urdf.mesh_robot import write_robot

RIM = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)


def _pose(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def _rims(world: object) -> np.ndarray:
    """(L, 32, 4) homogeneous points on each body cylinder's two rims, in its own frame."""
    radius, half = world._radius, world._half  # type: ignore[attr-defined]
    points = np.ones((len(radius), 2 * len(RIM), 4))
    for k, (r, h) in enumerate(zip(radius, half, strict=True)):
        for s, z in enumerate((-h, h)):
            rows = slice(s * len(RIM), (s + 1) * len(RIM))
            points[k, rows, 0], points[k, rows, 1], points[k, rows, 2] = (
                r * np.cos(RIM), r * np.sin(RIM), z)
    return points


def _bodies_at(world: object, q: np.ndarray) -> np.ndarray:
    """The body cylinders' poses (L, 4, 4) by Pinocchio (the collision world's own FK)."""
    world.set_configuration(q)  # type: ignore[attr-defined]
    return np.array(world._world)  # type: ignore[attr-defined]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), horizon=st.integers(1, 48))
def test_within_the_horizon_no_kr60_body_moves_more_than_its_bound_here(
        kr60: Robot, seed: int, horizon: int) -> None:
    _bound_holds(kr60, seed, horizon, 0.01)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), horizon=st.integers(1, 48))
def test_within_the_horizon_no_fanuc_body_moves_more_than_its_bound_here(
        fanuc: Robot, seed: int, horizon: int) -> None:
    _bound_holds(fanuc, seed, horizon, 0.01)


def _bound_here(world: object, a: np.ndarray, per_step: np.ndarray, horizon: int
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The kernel's motion bound at ``a`` (joints changing by ``per_step`` each step, on a
    segment of 200 steps) for ``horizon`` steps: the global cumulative bound (L, n + 1), the
    bound here (L, n + 1), each body's motion per step (L,), and the bodies' poses (L, 3, 4)."""
    compiled = world._compiled  # type: ignore[attr-defined]
    packed = compiled.packed
    joints, zero, links = packed.joints, packed.zero, packed.links
    n = len(a)
    levers = np.ascontiguousarray(compiled.link_levers())
    step, global_cum, growth, _ = bounds_walk.segment_levers(a, a + per_step * 200, 200, levers,
                                                             links)
    frames, poses = np.empty((n + 1, 3, 4)), np.empty((zero.shape[0], 3, 4))
    poses_into(a, joints, zero, links, frames, poses)
    seg = np.empty((6, zero.shape[0], 3))
    bounds.axis_segments(poses, links, seg)
    cum, move = np.zeros_like(global_cum), np.zeros(zero.shape[0])
    bounds_walk.motion_here(seg, frames, joints, links, step, growth, float(horizon), global_cum,
                            cum, move)
    return global_cum, cum, move, poses


def _bound_holds(robot: Robot, seed: int, horizon: int, largest_step: float) -> None:
    rng = np.random.default_rng(seed)
    n = len(robot.chain.lower())
    a = rng.uniform(robot.chain.lower(), robot.chain.upper())
    per_step = rng.uniform(-largest_step, largest_step, n) * (rng.random(n) < 0.8)
    _bound_holds_from(robot, a, per_step, horizon)


def _bound_holds_from(robot: Robot, a: np.ndarray, per_step: np.ndarray, horizon: int) -> None:
    """Every rim point of every body, at every step up to the horizon (both ways), stays within
    step x the bound on the body's motion at ``a`` (joints changing by ``per_step`` each step),
    and each body's points move relative to an earlier body within step x what the joints
    between them allow."""
    world = robot.collision_world()
    n, links = len(a), world.verdicts.packed.links
    global_cum, cum, move, poses = _bound_here(world, a, per_step, horizon)
    assert (cum <= global_cum + 1e-15).all() and (move <= global_cum[:, n] + 1e-15).all()
    here = _bodies_at(world, a)
    np.testing.assert_allclose(here[:, :3], poses, atol=1e-9)  # (the same bodies, in order)
    rims = _rims(world)
    start = np.einsum("kij,kpj->kpi", here, rims)
    moved = links[:, MOVED].astype(int)
    for t in range(1, horizon + 1):
        for sign in (1.0, -1.0):
            there = _bodies_at(world, a + sign * t * per_step)
            points = np.einsum("kij,kpj->kpi", there, rims)
            travel = np.linalg.norm(points - start, axis=2).max(axis=1)
            assert (travel <= t * move * (1 + 1e-9) + 1e-12).all(), (t, travel, t * move)
            for i in range(len(moved)):
                for j in range(len(moved)):
                    if moved[i] >= moved[j]:
                        continue
                    ref_0, ref_t = np.linalg.inv(here[i]), np.linalg.inv(there[i])
                    rel = np.linalg.norm(
                        (ref_t @ there[j] @ rims[j].T - ref_0 @ here[j] @ rims[j].T)[:3], axis=0)
                    closing = cum[j, moved[j]] - cum[j, moved[i]]
                    assert rel.max() <= t * closing * (1 + 1e-9) + 1e-12, (t, i, j)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), horizon=st.integers(1, 40))
def test_each_joints_lever_arm_here_holds_over_the_horizon(kr60: Robot, seed: int,
                                                          horizon: int) -> None:
    """Joint by joint, the bound's share (how far joint j moves body k per step) covers the
    average over the first t steps of the farthest rim point's distance from j's axis, times
    j's change per step, for every t up to the horizon (both ways): the distance from the axis
    by Pinocchio's Jacobian (a point's speed per unit of a revolute joint), at a quarter step's
    resolution. The joints after j move the body away from its axis as the steps go on, which
    the bound must include: without that term it fails here."""
    world = kr60.collision_world()
    links = world.verdicts.packed.links
    rng = np.random.default_rng(seed)
    n = len(kr60.chain.lower())
    a = rng.uniform(kr60.chain.lower(), kr60.chain.upper())
    per_step = rng.uniform(-0.03, 0.03, n) * (rng.random(n) < 0.8)
    cum = _bound_here(world, a, per_step, horizon)[1]
    rims = _rims(world)
    for sign in (1.0, -1.0):
        fractions = np.arange(4 * horizon + 1) / 4.0
        reach = np.zeros((len(fractions), len(rims), n))  # farthest rim point from each axis
        for f, s in enumerate(fractions):
            q = a + sign * s * per_step
            for k, (link, local) in enumerate(zip(world._links, world._local, strict=True)):
                placed, jac = world.kinematics.pose_and_jacobian(q, link)
                centre = placed @ local @ rims[k].T  # (4, 32): the rim points
                offset = centre[:3] - placed[:3, 3:4]
                speed = jac[:3, :, None] + np.cross(jac[3:].T[:, :, None], offset[None], axis=1
                                                    ).transpose(1, 0, 2)
                reach[f, k] = np.linalg.norm(speed, axis=0).max(axis=1)
        for t in range(1, horizon + 1):
            mean = (reach[: 4 * t + 1].sum(axis=0) - (reach[0] + reach[4 * t]) / 2) / (4 * t)
            for k in range(len(rims)):
                for j in range(int(links[k, MOVED])):
                    share = cum[k, j + 1] - cum[k, j]
                    assert abs(per_step[j]) * mean[k, j] <= share * (1 + 1e-6) + 1e-9, (
                        sign, t, k, j, abs(per_step[j]) * mean[k, j], share)


def _sweep(kr60: Robot) -> tuple[object, np.ndarray, np.ndarray, int]:
    """The KR60 turning on axis 1 past a pillar: free at both ends, in contact over the middle
    third of the segment (asserted on every configuration)."""
    world = kr60.collision_world(Scene("pillar", (
        SceneObject("pillar", Box((0.6, 1.2, 2.4)), _pose(1.7, 0.0, 1.2)),)))
    a = np.array([-0.8, -1.2, 1.9, 0.0, 0.6, 0.0])
    b = a.copy()
    b[0] = 0.8
    steps = 240
    every = world.in_collision_many(np.linspace(a, b, steps + 1))
    assert not every[0] and not every[-1]
    assert every[steps // 3: 2 * steps // 3 + 1].all()
    return world, a, b, steps


def test_a_segment_blocked_in_its_middle_ends_at_the_third_configuration(kr60: Robot) -> None:
    """The ends first, then the middle of what they leave unproven: the third evaluation lies in
    the middle third, in contact, whatever the ends prove."""
    world, a, b, steps = _sweep(kr60)
    decided: list[int] = []

    def in_contact(poses: np.ndarray, row: np.ndarray) -> bool:
        decided.append(1)
        return world._any_contact(poses, row)  # type: ignore[attr-defined]

    free, evaluated = world._compiled.segment_free(a, b, steps, in_contact)  # type: ignore
    assert not free and evaluated == 3
    assert world.segment_free(a, b, steps) is False  # type: ignore[attr-defined]


def test_a_free_segment_needs_few_evaluations_where_its_clearance_is_large(kr60: Robot) -> None:
    """Turning away from the pillar: every configuration free, proven by a few of them."""
    world, a, b, steps = _sweep(kr60)
    b = a.copy()
    b[0] = -1.6
    assert not world.in_collision_many(np.linspace(a, b, steps + 1)).any()
    free, evaluated = world._compiled.segment_free(  # type: ignore[attr-defined]
        a, b, steps, lambda poses, row: True)
    assert free and evaluated <= 10  # measured: 5 of the 241


def test_each_undecided_configuration_goes_to_the_exact_judge_as_it_comes(
        tmp_path: Path) -> None:
    """A mesh arm near obstacles: its bounding volumes leave configurations undecided, and the
    walk stops at the first one the judge finds in contact; a judge that finds none lets it
    run to the end, asked once per undecided configuration."""
    urdf, srdf = write_robot(tmp_path)
    robot = robot_from_files(urdf, srdf)
    world = robot.collision_world(Scene("test", (
        SceneObject("table", Box((1.0, 1.0, 0.04)), _pose(0.0, 0.0, -0.02), ("base_link",)),
        SceneObject("ball", Sphere(0.08), _pose(0.25, 0.1, 0.45)))))
    rng = np.random.default_rng(7)
    lo, hi = robot.chain.lower(), robot.chain.upper()
    asked_most = 0
    for _ in range(200):
        a = rng.uniform(lo, hi)
        b = np.clip(a + rng.normal(0.0, 0.4, len(lo)), lo, hi)
        never, first = _Judge(False), _Judge(True)
        free, evaluated = world._compiled.segment_free(a, b, 60, never)
        blocked, _ = world._compiled.segment_free(a, b, 60, first)
        if never.asked:
            assert first.asked == 1 and not blocked
        else:
            assert first.asked == 0 and blocked == free
        assert never.asked <= evaluated
        asked_most = max(asked_most, never.asked)
    assert asked_most >= 2


class _Judge:
    """An exact judge that gives one answer and counts how often it was asked."""

    def __init__(self, answer: bool) -> None:
        self.answer, self.asked = answer, 0

    def __call__(self, poses: np.ndarray, row: np.ndarray) -> bool:
        self.asked += 1
        return self.answer


def test_a_capped_judge_gives_the_same_verdicts_and_the_smaller_of_cap_and_gap(
        tmp_path: Path) -> None:
    """The walk never proves more than its horizon, so it caps the judge there: subtrees,
    refinements and pairs whose bounds lie above the cap are skipped. That changes nothing below
    the cap: over random configurations and motions of a mesh arm among obstacles, the verdicts
    are those of the uncapped judge and each gap (self, scene) is the smaller of the cap and the
    uncapped gap, to the bit."""
    urdf, srdf = write_robot(tmp_path)
    robot = robot_from_files(urdf, srdf)
    objects = []
    rng = np.random.default_rng(11)
    for k in range(8):  # (around the arm: some configurations clear them all, some do not)
        angle, reach, z = rng.uniform((0.0, 0.4, 0.0), (2.0 * np.pi, 0.7, 0.6))
        shape = Box(tuple(rng.uniform(0.03, 0.2, 3))) if k % 2 else Sphere(rng.uniform(0.03, 0.08))
        objects.append(SceneObject(f"o{k}", shape,
                                   _pose(reach * np.cos(angle), reach * np.sin(angle), z)))
    world = robot.collision_world(Scene("test", tuple(objects)))
    packed = world.verdicts.packed
    links = packed.links
    n_link = len(links)
    seg = np.empty((6, n_link, 3))
    lo, hi = robot.chain.lower(), robot.chain.upper()
    below = above = self_below = self_above = 0
    for q in rng.uniform(lo, hi, (300, len(lo))):
        poses = bounds.check(q[None], packed, bounds.EPS, bounds.MARGIN)[0][0]
        bounds.axis_segments(poses, links, seg)
        move = rng.uniform(1e-4, 4e-3, n_link)
        cum = np.cumsum(rng.uniform(0.0, 0.02, (n_link, len(lo) + 1)), axis=1)
        row, (self_gap, scene_gap) = _judged(packed, poses, seg, move, cum, np.inf)
        for cap in (1.0, 4.0, 16.0, 64.0):
            capped_row, (capped_self, capped_scene) = _judged(packed, poses, seg, move, cum, cap)
            assert np.array_equal(capped_row, row)
            assert capped_scene == min(cap, scene_gap), (q.tolist(), cap)
            assert capped_self == min(cap, self_gap), (q.tolist(), cap)
            below += scene_gap < cap
            above += scene_gap > cap
            self_below += self_gap < cap
            self_above += self_gap > cap
    assert below > 100 and above > 100, (below, above)
    assert self_below > 100 and self_above > 100, (self_below, self_above)


def _judged(packed: Packed, poses: np.ndarray, seg: np.ndarray, move: np.ndarray,
            cum: np.ndarray, cap: float) -> tuple[np.ndarray, tuple[float, float]]:
    """The compiled judge's verdicts and gaps (self, scene) at one configuration, capped."""
    row = np.zeros(len(packed.pairs), dtype=np.int8)
    stack = np.empty(max(1, len(packed.nodes)), dtype=np.int64)
    gaps = bounds.judge_pairs(seg, poses, packed, bounds.EPS, bounds.MARGIN, move, cum,
                              bounds.REFINE, cap, row, np.empty((8, 3)), np.empty(3), stack,
                              bounds.ball_scratch(packed.links, packed.groups, packed.leaves))
    return row, gaps
