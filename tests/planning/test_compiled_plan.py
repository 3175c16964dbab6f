"""The compiled planner (planning/plan_kernel.py, compiled_plan.py): its edges are proofs, its
paths free at the path check's density by the exact judge, its plans decided by the seed, and
OMPL plans where it finds nothing."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from tests.planning.recheck import blocked_pairs
from usar_arm.planning import bounds, compiled_plan, plan_kernel
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ompl_adapter import COMPILED, OmplOptions, edge_configurations, reseed
from usar_arm.planning.ptp import plan_to_joints
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene_file import load_scene


def _plan(world: CollisionWorld, robot: Robot, a: np.ndarray, b: np.ndarray,
          options: OmplOptions) -> np.ndarray:
    chain = robot.chain
    return plan_to_joints(world, chain.joint_names, chain.lower(), chain.upper(), a, b,
                          options).waypoints


@pytest.mark.parametrize("scene", ["table", "cage", "shelf"])
def test_every_configuration_of_a_compiled_path_is_free_by_the_exact_judge(
        kr60: Robot, scene: str) -> None:
    world = kr60.collision_world(load_scene(scene))
    levers, options = world.lever_arms(), OmplOptions()
    for a, b in blocked_pairs(world, kr60, 3, seed=5):
        found = compiled_plan.plan_compiled(world, kr60.chain.lower(), kr60.chain.upper(), a,
                                            b, options)
        assert found is not None and found.planner == COMPILED
        path = found.waypoints
        assert np.array_equal(path[0], a) and np.array_equal(path[-1], b) and len(path) > 2
        for p, q in itertools.pairwise(path):  # (at the path check's density, and finer)
            dense = edge_configurations(p, q, options.resolution, levers, options.max_step / 4)
            assert not world.in_collision_many(dense).any()
        assert found.states_checked > 0 and found.edges_checked > 0


def test_a_compiled_edge_is_taken_only_when_proven_free(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    arm, links, packed = world.lever_arms(), world.link_levers(), world.verdicts.packed
    evaluated = np.zeros(1, dtype=np.int64)
    rng = np.random.default_rng(3)
    taken = blocked = 0
    for _ in range(60):
        a, b = rng.uniform(kr60.chain.lower(), kr60.chain.upper(), size=(2, 6))
        clear = plan_kernel.edge_clear(a, b, arm, links, 0.01, 0.005, packed, bounds.EPS,
                                       bounds.MARGIN, evaluated)
        dense = edge_configurations(a, b, 0.01, arm, 0.005)
        hit = world.in_collision_many(dense).any()
        assert not (clear and hit), "an edge in contact was taken"
        taken += clear
        blocked += hit
    assert taken > 5 and blocked > 5 and evaluated[0] > 0


def test_a_plan_depends_on_its_seed_alone(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("cage"))
    a, b = blocked_pairs(world, kr60, 1, seed=8)[0]
    reseed(4)
    first = _plan(world, kr60, a, b, OmplOptions())
    for other in blocked_pairs(world, kr60, 2, seed=9):  # (other plans in between)
        _plan(world, kr60, *other, OmplOptions())
    reseed(4)
    assert np.array_equal(_plan(world, kr60, a, b, OmplOptions()), first)


def test_ompl_plans_where_the_compiled_search_runs_out_of_edges(
        kr60: Robot, monkeypatch: pytest.MonkeyPatch) -> None:
    world = kr60.collision_world(load_scene("cage"))
    a, b = blocked_pairs(world, kr60, 1, seed=8)[0]
    monkeypatch.setattr(compiled_plan, "MAX_EDGES", 1)
    chain = kr60.chain
    plan = plan_to_joints(world, chain.joint_names, chain.lower(), chain.upper(), a, b,
                          OmplOptions())
    assert plan.ompl is not None and plan.ompl.planner == "RRTConnect"
    levers = world.lever_arms()
    for p, q in itertools.pairwise(plan.waypoints):
        assert not world.in_collision_many(edge_configurations(p, q, 0.01, levers,
                                                               0.005)).any()


def test_random_shortcuts_keep_the_ends_and_shorten_a_free_path(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("empty"))
    arm, links, packed = world.lever_arms(), world.link_levers(), world.verdicts.packed
    rng = np.random.default_rng(1)
    path = np.cumsum(rng.uniform(-0.1, 0.1, size=(12, 6)), axis=0)  # a wandering free path
    assert not world.in_collision_many(path).any()
    shorter = plan_kernel.shortcut(path, arm, links, 0.01, 0.005, 30, 7, packed, bounds.EPS,
                                   bounds.MARGIN)
    assert np.array_equal(shorter[0], path[0]) and np.array_equal(shorter[-1], path[-1])

    def length(p: np.ndarray) -> float:
        return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())

    assert length(shorter) < length(path)
    evaluated = np.zeros(1, dtype=np.int64)
    for p, q in itertools.pairwise(shorter):
        assert plan_kernel.edge_clear(p, q, arm, links, 0.01, 0.005, packed, bounds.EPS,
                                      bounds.MARGIN, evaluated)


def _undecided_free(world: CollisionWorld, robot: Robot, count: int, seed: int
                    ) -> list[np.ndarray]:
    """Free configurations (by the exact judge) the bounding volumes leave undecided: ends
    close to an obstacle, as a grasp is."""
    rng = np.random.default_rng(seed)
    found: list[np.ndarray] = []
    while len(found) < count:
        q = rng.uniform(robot.chain.lower(), robot.chain.upper())
        if (world.verdicts.summary(q)[0] == bounds.UNDECIDED and not world.in_collision(q)):
            found.append(q)
    return found


def test_an_undecided_end_is_left_by_an_escape_the_exact_judge_finds_free(
        kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    chain, options, levers = kr60.chain, OmplOptions(), world.lever_arms()
    rng = np.random.default_rng(2)
    for end in _undecided_free(world, kr60, 4, seed=11):
        out = compiled_plan.escape(world, end, np.zeros(6), chain.lower(), chain.upper(),
                                   options, rng)
        assert out is not None
        assert world.verdicts.summary(out)[0] == bounds.CLEAR
        assert np.linalg.norm(out - end) <= max(compiled_plan.ESCAPE_RADII) + 1e-9
        dense = edge_configurations(end, out, options.resolution, levers, options.max_step / 4)
        assert not world.in_collision_many(dense).any()


def test_the_compiled_planner_plans_from_and_to_undecided_ends(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("table"))
    chain, options, levers = kr60.chain, OmplOptions(), world.lever_arms()
    a, b = _undecided_free(world, kr60, 2, seed=12)
    reseed(3)
    found = compiled_plan.plan_compiled(world, chain.lower(), chain.upper(), a, b, options)
    assert found is not None and found.planner == COMPILED
    path = found.waypoints
    assert np.array_equal(path[0], a) and np.array_equal(path[-1], b) and len(path) >= 4
    for p, q in itertools.pairwise(path):
        dense = edge_configurations(p, q, options.resolution, levers, options.max_step / 4)
        assert not world.in_collision_many(dense).any()
