"""A reachability map says what the arm does: every voxel it marks has a witness that an
independent check accepts (Pinocchio FK on the URDF, FCL brute force), poses the arm reaches
land in marked voxels (up to the voxel at the edge of the reach), nothing beyond the reach
bound is marked, and the arrays are what reach.npz promises."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from usar_arm import jobs
from usar_arm.planning.scene import EMPTY
from usar_arm.planning.scene_file import load_scene
from usar_arm.robot import Robot
from usar_arm.workspace.grid import reach_bound
from usar_arm.workspace.orientations import quaternions_to_matrices
from usar_arm.workspace.reach import ReachSettings
from usar_arm.workspace.reach_map import ReachMap

from .conftest import SMALL


def test_the_arrays_have_the_promised_shapes_types_and_ranges(small_map: jobs.ReachRun) -> None:
    m = small_map.map
    assert m.index.dtype == np.float32 and m.index.ndim == 3
    assert m.manipulability.shape == m.index.shape == m.margin.shape
    assert m.best_q.shape == (*m.index.shape, 6)
    assert m.origin.shape == (3,) and m.resolution == SMALL.resolution
    assert np.all((m.index >= 0) & (m.index <= 1))
    assert len(m.orientations) == SMALL.orientations
    bits = np.unpackbits(m.reachable, axis=-1, count=len(m.orientations))
    assert np.allclose(bits.mean(axis=-1), m.index)
    reached = m.index > 0
    assert np.all(m.manipulability[reached] > 0) and np.all(m.manipulability[~reached] == 0)
    assert np.all(np.isnan(m.best_q[~reached])) and np.all(m.best_orientation[~reached] == -1)
    assert 0.1 < reached.mean() < 0.6


def test_every_marked_voxel_has_a_witness_an_independent_check_accepts(
        small_map: jobs.ReachRun, kr60: Robot) -> None:
    m = small_map.map
    world = kr60.collision_world(EMPTY)
    rotations = quaternions_to_matrices(m.orientations)
    rng = np.random.default_rng(11)
    marked = np.argwhere(m.index > 0)
    for i, j, k in marked[rng.choice(len(marked), 300, replace=False)]:
        q = m.best_q[i, j, k]
        pose = kr60.kinematics.frame_pose(q, "tool0")
        assert np.linalg.norm(pose[:3, 3] - m.centre(i, j, k)) < 2e-5
        rot = rotations[m.best_orientation[i, j, k]]
        assert np.linalg.norm(pose[:3, :3] - rot) < 1e-4
        assert m.reached(i, j, k)[m.best_orientation[i, j, k]]
        assert not world.contacts_brute_force(q)
        assert np.all(q >= kr60.chain.lower()) and np.all(q <= kr60.chain.upper())


def test_nothing_beyond_the_reach_bound_is_marked(small_map: jobs.ReachRun, kr60: Robot) -> None:
    m = small_map.map
    bound = reach_bound(kr60.chain)
    centres = m.origin + np.argwhere(m.index > 0) * m.resolution
    assert bound.distance(centres).max() <= bound.radius
    outside = np.argwhere(m.index == 0)
    far = outside[bound.distance(m.origin + outside * m.resolution) > bound.radius + 0.01]
    assert len(far) > 0 and np.all(m.index[tuple(far.T)] == 0)


def test_poses_the_arm_reaches_land_in_marked_voxels_or_beside_one(kr60: Robot) -> None:
    """10,000 random collision-free configurations of the KR60 in the table scene: where its
    tool0 lands, the map's index is > 0, or (at the edge of the reach, where the voxel's centre
    lies just outside it) a neighbouring voxel's is. The index is a property of the voxel's
    centre, so a pose near the edge of the reach can land in a voxel whose centre the arm
    cannot reach. Measured on this 20 cm, 64-orientation map: 96.2 % in a marked voxel and
    every other one beside one (at 10 cm: 98.2 %; bench stage workspace)."""
    scene = load_scene("table")
    run = jobs.reach_map(kr60, scene, ReachSettings(0.2, 64), jobs.backend_for(0))
    m = run.map
    world = kr60.collision_world(scene)
    rng = np.random.default_rng(5)
    qs = rng.uniform(kr60.chain.lower(), kr60.chain.upper(), size=(30_000, 6))
    qs = qs[~world.in_collision_many(qs)][:10_000]
    assert len(qs) == 10_000
    points = np.array([kr60.kinematics.frame_pose(q, "tool0")[:3, 3] for q in qs])
    inside = m.lookup(points) > 0
    assert inside.mean() > 0.96
    padded = np.pad(m.index > 0, 1)
    for ijk in m.voxel_of(points[~inside]) + 1:
        i, j, k = ijk
        assert padded[i - 1:i + 2, j - 1:j + 2, k - 1:k + 2].any(), ijk


def test_the_map_is_the_same_every_time_and_survives_its_file(small_map: jobs.ReachRun,
                                                              kr60: Robot,
                                                              tmp_path: Path) -> None:
    again = jobs.reach_map(kr60, EMPTY, SMALL, jobs.backend_for(0)).map
    a = small_map.map
    for name in ("index", "manipulability", "margin", "best_orientation", "reachable"):
        assert np.array_equal(getattr(a, name), getattr(again, name))
    assert np.array_equal(a.best_q, again.best_q, equal_nan=True)
    path = a.save(tmp_path / "reach.npz")
    back = ReachMap.load(path)
    assert np.array_equal(back.index, a.index) and back.joint_names == a.joint_names
    assert np.array_equal(back.best_q, a.best_q, equal_nan=True)
    assert back.resolution == a.resolution and np.array_equal(back.origin, a.origin)
