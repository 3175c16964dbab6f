"""The sphere tree over a scene's obstacles (usar_arm.planning.scene_tree): every obstacle lies
inside the sphere of every node above it, and a world that uses the tree answers as python-fcl
does, pair by pair, in crowded scenes (brute force shares no code with the tree)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.planning.test_bounds import _agree, _pose
from usar_arm.planning import scene_tree
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, SceneObject, Sphere


def _crowd(rng: np.random.Generator, count: int) -> Scene:
    """``count`` small obstacles of every kind scattered through the arm's reach."""
    objects = []
    for k in range(count):
        pose = _pose(rng.normal(size=3), rng.uniform([-2.8, -2.8, -0.3], [2.8, 2.8, 3.0]))
        kind = k % 4
        if kind == 0:
            shape: object = Box(tuple(rng.uniform(0.02, 0.15, 3)))
        elif kind == 1:
            shape = CylinderShape(float(rng.uniform(0.01, 0.08)), float(rng.uniform(0.02, 0.3)))
        elif kind == 2:
            shape = Sphere(float(rng.uniform(0.01, 0.1)))
        else:  # a tetrahedron
            v = rng.uniform(-0.08, 0.08, (4, 3))
            shape = Mesh(v, np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]))
        objects.append(SceneObject(f"o{k}", shape, pose))  # type: ignore[arg-type]
    return Scene("crowd", tuple(objects))


def _ancestors(nodes: np.ndarray) -> dict[int, list[int]]:
    up: dict[int, list[int]] = {0: []}
    for parent, (left, right, _, _) in enumerate(nodes):
        for child in (left, right):
            if child >= 0:
                up[int(child)] = [*up[parent], parent]
    return up


@settings(max_examples=60, deadline=None)
@given(st.integers(min_value=0, max_value=300), st.integers(min_value=0, max_value=2**31))
def test_every_obstacle_lies_inside_each_node_above_it(count: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    centres = rng.normal(0.0, rng.uniform(0.01, 5.0), (count, 3))
    radii = rng.uniform(0.0, 1.0, count)
    spheres, nodes, order = scene_tree.build(centres, radii)
    assert sorted(order.tolist()) == list(range(count))
    if count == 0:
        assert len(nodes) == 0
        return
    up = _ancestors(nodes)
    leaves = [k for k, (left, _, _, _) in enumerate(nodes) if left < 0]
    covered = sorted(int(s) for k in leaves for s in order[nodes[k, 2]:nodes[k, 3]])
    assert covered == list(range(count))  # each obstacle in exactly one leaf
    for k in leaves:
        assert nodes[k, 3] - nodes[k, 2] <= max(scene_tree.LEAF_SIZE, scene_tree.MIN_OBSTACLES)
        for s in order[nodes[k, 2]:nodes[k, 3]]:
            for nd in [*up[k], k]:
                reach = np.linalg.norm(centres[s] - spheres[nd, :3]) + radii[s]
                assert reach <= spheres[nd, 3], (count, s, nd)


def test_the_pair_table_names_each_checked_pair_once() -> None:
    rs = np.array([[0, 2], [1, 0], [2, 2]])
    table = scene_tree.pair_table(rs, 5, 3, 4)
    assert table.tolist() == [[-1, -1, 5, -1], [6, -1, -1, -1], [-1, -1, 7, -1]]


@pytest.mark.parametrize("count", [16, 60, 250])
def test_a_crowded_world_agrees_with_brute_force(kr60: Robot, count: int) -> None:
    rng = np.random.default_rng(count)
    world = kr60.collision_world(_crowd(rng, count), padding=float(rng.uniform(0, 0.03)))
    qs = rng.uniform(kr60.chain.lower(), kr60.chain.upper(), (300 if count < 250 else 120, 6))
    _, colliding = _agree(world, qs)
    assert 0 < colliding < len(qs)


def test_a_segment_walk_in_a_crowded_world_answers_as_checking_every_configuration(
        kr60: Robot) -> None:
    rng = np.random.default_rng(31)
    world = kr60.collision_world(_crowd(rng, 60))
    lo, hi = kr60.chain.lower(), kr60.chain.upper()
    outcomes = set()
    for _ in range(60):
        a = rng.uniform(lo, hi)
        b = np.clip(a + rng.normal(0.0, 0.3, 6), lo, hi)
        steps = int(rng.integers(1, 200))
        qs = a + (b - a) * (np.arange(steps + 1) / steps)[:, None]
        truth = not any(world.contacts_brute_force(q) for q in qs)
        assert world.segment_free(a, b, steps) == truth, (a.tolist(), b.tolist(), steps)
        outcomes.add(truth)
    assert outcomes == {True, False}
