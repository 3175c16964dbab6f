"""A reachability map says what the arm does: every voxel it marks has a witness that an
independent check accepts (Pinocchio FK on the URDF, FCL brute force): tool0 at the centre in
the named orientation, or, for an edge voxel, inside the cell in an orientation nearer the named
one than any other; every pose the arm reaches lands in a marked voxel; nothing beyond the reach
bound is marked; and the arrays are what reach.npz promises."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import EMPTY
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace import jobs
from usar_arm.workspace.grid import reach_bound
from usar_arm.workspace.orientations import quaternions_to_matrices
from usar_arm.workspace.reach import ReachSettings
from usar_arm.workspace.reach_map import ReachMap

from .conftest import SMALL


def test_the_arrays_have_the_promised_shapes_types_and_ranges(small_map: jobs.ReachRun) -> None:
    m = small_map.map
    assert m.index.dtype == np.float32 and m.index.ndim == 3
    assert m.manipulability.shape == m.index.shape == m.margin.shape == m.edge.shape
    assert m.edge.dtype == bool
    assert m.best_q.shape == (*m.index.shape, 6)
    assert m.origin.shape == (3,) and m.resolution == SMALL.resolution
    assert np.all((m.index >= 0) & (m.index <= 1))
    assert len(m.orientations) == SMALL.orientations
    bits = np.unpackbits(m.reachable, axis=-1, count=len(m.orientations))
    assert np.allclose(bits.mean(axis=-1), m.index)
    reached = m.index > 0
    assert np.all(reached[m.edge]) and m.edge.any()
    assert np.all(m.index[m.edge] == np.float32(1 / len(m.orientations)))
    assert np.all(m.manipulability[reached] > 0) and np.all(m.manipulability[~reached] == 0)
    assert np.all(np.isnan(m.best_q[~reached])) and np.all(m.best_orientation[~reached] == -1)
    assert 0.1 < reached.mean() < 0.6


def _nearest(rotations: np.ndarray, rot: np.ndarray) -> int:
    """The row of ``rotations`` nearest ``rot`` (the largest trace of R_o^T R: the smallest
    angle)."""
    return int(np.argmax([np.trace(r.T @ rot) for r in rotations]))


def test_every_marked_voxel_has_a_witness_an_independent_check_accepts(
        small_map: jobs.ReachRun, kr60: Robot) -> None:
    m = small_map.map
    world = kr60.collision_world(EMPTY)
    rotations = quaternions_to_matrices(m.orientations)
    rng = np.random.default_rng(11)
    centre = np.argwhere((m.index > 0) & ~m.edge)
    edge = np.argwhere(m.edge)
    picked = [(v, False) for v in centre[rng.choice(len(centre), 300, replace=False)]]
    picked += [(v, True) for v in edge[rng.choice(len(edge), min(200, len(edge)),
                                                  replace=False)]]
    for (i, j, k), on_edge in picked:
        q = m.best_q[i, j, k]
        pose = kr60.kinematics.frame_pose(q, "tool0")
        o = m.best_orientation[i, j, k]
        if on_edge:
            assert np.max(np.abs(pose[:3, 3] - m.centre(i, j, k))) <= m.resolution / 2
            assert _nearest(rotations, pose[:3, :3]) == o
        else:
            assert np.linalg.norm(pose[:3, 3] - m.centre(i, j, k)) < 2e-5
            assert np.linalg.norm(pose[:3, :3] - rotations[o]) < 1e-4
        assert m.reached(i, j, k)[o]
        assert not world.contacts_brute_force(q)
        assert np.all(q >= kr60.chain.lower()) and np.all(q <= kr60.chain.upper())


def test_nothing_beyond_the_reach_bound_is_marked(small_map: jobs.ReachRun, kr60: Robot) -> None:
    m = small_map.map
    bound = reach_bound(kr60.chain)
    centres = m.origin + np.argwhere((m.index > 0) & ~m.edge) * m.resolution
    assert bound.distance(centres).max() <= bound.radius
    edges = m.origin + np.argwhere(m.edge) * m.resolution  # part of the cell is within it
    assert bound.distance(edges).max() <= bound.radius + m.resolution * np.sqrt(3) / 2
    outside = np.argwhere(m.index == 0)
    far = outside[bound.distance(m.origin + outside * m.resolution) > bound.radius + 0.01]
    assert len(far) > 0 and np.all(m.index[tuple(far.T)] == 0)


def _reachable_points(robot: Robot, world: CollisionWorld, count: int, seed: int) -> np.ndarray:
    """tool0 at ``count`` random collision-free configurations (uniform within the limits)."""
    rng = np.random.default_rng(seed)
    qs = rng.uniform(robot.chain.lower(), robot.chain.upper(), size=(4 * count, robot.chain.dof))
    qs = qs[~world.in_collision_many(qs)][:count]
    assert len(qs) == count
    return np.array([robot.kinematics.frame_pose(q, "tool0")[:3, 3] for q in qs])


def test_every_pose_the_arm_reaches_lands_in_a_marked_voxel(kr60: Robot) -> None:
    """10,000 random collision-free configurations of the KR60 in the table scene (floor,
    table, tower, bin...): tool0 lands in a voxel of index > 0, every time. Without the edge
    search it does not: voxels whose centre the arm cannot reach (beyond the reach, inside the
    floor or the table, behind the tower) hold reachable poses, and the test measures that
    share too, so it is known to be able to fail."""
    scene = load_scene("table")
    points = _reachable_points(kr60, kr60.collision_world(scene), 10_000, seed=5)
    centres_only = jobs.reach_map(kr60, scene, ReachSettings(0.2, 64, edges=False),
                                  jobs.backend_for(0)).map
    assert np.mean(centres_only.lookup(points) == 0) > 0.01
    run = jobs.reach_map(kr60, scene, ReachSettings(0.2, 64), jobs.backend_for(0))
    missed = points[run.map.lookup(points) == 0]
    assert len(missed) == 0, f"{len(missed)} reachable poses in voxels of index 0: {missed[:5]}"
    assert run.edges is not None and run.edges.draws is not None
    assert 0 <= run.edges.draws.miss_rate < 1e-4


def test_the_map_is_the_same_every_time_and_survives_its_file(small_map: jobs.ReachRun,
                                                              kr60: Robot,
                                                              tmp_path: Path) -> None:
    again = jobs.reach_map(kr60, EMPTY, SMALL, jobs.backend_for(0)).map
    a = small_map.map
    for name in ("index", "manipulability", "margin", "best_orientation", "reachable", "edge"):
        assert np.array_equal(getattr(a, name), getattr(again, name))
    assert np.array_equal(a.best_q, again.best_q, equal_nan=True)
    path = a.save(tmp_path / "reach.npz")
    back = ReachMap.load(path)
    assert np.array_equal(back.index, a.index) and back.joint_names == a.joint_names
    assert np.array_equal(back.best_q, a.best_q, equal_nan=True)
    assert back.resolution == a.resolution and np.array_equal(back.origin, a.origin)
    assert np.array_equal(back.edge, a.edge)
