"""A robot's collision worlds are copies of one world of the empty scene (what depends on the
arm alone is built once): each answers as a world built from scratch for its scene, padding and
disabled pairs, and using one never disturbs another."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from usar_arm.core.shapes import Box, Sphere
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.robot import robot_from_files
from usar_arm.planning.scene import EMPTY, Scene, SceneObject

from ..urdf.mesh_robot import write_robot


def _pose(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


TABLE = Scene("table", (SceneObject("table", Box((1.0, 1.0, 0.04)), _pose(0.0, 0.0, -0.02),
                                    ("base_link",)),
                        SceneObject("ball", Sphere(0.08), _pose(0.25, 0.1, 0.45))))
SHELF = Scene("shelf", (SceneObject("board", Box((0.3, 0.6, 0.02)), _pose(0.3, 0.0, 0.3)),))


def test_worlds_of_a_robot_answer_as_worlds_built_from_scratch(tmp_path: Path) -> None:
    urdf, srdf = write_robot(tmp_path)
    robot = robot_from_files(urdf, srdf)
    rng = np.random.default_rng(11)
    lo, hi = robot.chain.lower(), robot.chain.upper()
    qs = rng.uniform(lo, hi, (400, len(lo)))
    cases = [(TABLE, 0.0), (SHELF, 0.0), (EMPTY, 0.0), (TABLE, 0.0), (SHELF, 0.0)]
    copies = [robot.collision_world(scene, padding) for scene, padding in cases]
    for (scene, padding), ours in zip(cases, copies, strict=True):
        fresh = CollisionWorld(robot.chain, robot.kinematics, robot.disabled, scene, padding)
        assert ours.checked_pairs() == fresh.checked_pairs()
        assert ours.contacts_many(qs) == fresh.contacts_many(qs)
        np.testing.assert_array_equal(ours.lever_arms(), fresh.lever_arms())
        for a, b in zip(qs[:40], qs[40:80], strict=True):
            assert ours.segment_free(a, b, 60) == fresh.segment_free(a, b, 60)
    # interleaved use: a world's answer does not depend on what another was asked last
    first, second = copies[0], copies[1]
    for q in qs[:50]:
        expected = first.contacts(q)
        second.in_collision(qs[-1])
        assert first.contacts(q) == expected
    seen = {bool(first.in_collision(q)) for q in qs}
    assert seen == {False, True}  # both kinds of configuration were compared


def test_changing_the_disabled_pairs_gives_worlds_of_the_new_set(tmp_path: Path) -> None:
    urdf, srdf = write_robot(tmp_path)
    robot = robot_from_files(urdf, srdf)
    before = set(robot.collision_world().checked_pairs())
    robot.disabled = set()
    after = set(robot.collision_world().checked_pairs())
    assert before < after
    fresh = CollisionWorld(robot.chain, robot.kinematics, set(), EMPTY)
    assert after == set(fresh.checked_pairs())
