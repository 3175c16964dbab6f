"""The lazy collision verdicts of a batch of poses equal checking every solution with FCL
alone (the brute-force judge): the same reachable poses, the same best manipulability and the
same best margin."""

from __future__ import annotations

import numpy as np
import pytest

from usar_arm.planning.robot import Robot
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace.orientations import orientation_set
from usar_arm.workspace.query import judge
from usar_arm.workspace.solver import AllSolutions


@pytest.mark.parametrize("scene", ["table", "shelf", "cage"])
def test_lazy_verdicts_equal_checking_every_solution_by_brute_force(kr60: Robot,
                                                                    scene: str) -> None:
    world = kr60.collision_world(load_scene(scene))
    rng = np.random.default_rng(7)
    rots = orientation_set(16).matrices()
    centres = rng.uniform([-0.5, -1.5, 0.0], [2.2, 1.5, 1.8], size=(40, 3))
    all_rots = np.tile(rots, (len(centres), 1, 1))
    all_pos = np.repeat(centres, len(rots), axis=0)
    cand = AllSolutions(kr60.chain, kr60.ik_solver()).solve(all_rots, all_pos)
    v = judge(cand, world)
    assert 0.05 < v.reachable.mean() < 0.95  # the sample has both kinds of pose
    for k in range(len(all_pos)):
        free = [j for j in range(cand.count[k])
                if not world.contacts_brute_force(cand.q[k, j])]
        assert v.reachable[k] == bool(free)
        if free:
            assert v.manipulability[k] == max(cand.manipulability[k, j] for j in free)
            assert v.margin[k] == max(cand.margin[k, j] for j in free)
            assert not world.contacts_brute_force(v.q[k])
            assert np.isclose(cand.manipulability[k][
                np.argmin(np.abs(cand.q[k, :cand.count[k]] - v.q[k]).max(axis=1))],
                v.manipulability[k])
        else:
            assert np.isneginf(v.manipulability[k]) and np.all(np.isnan(v.q[k]))
    assert v.checks <= int(cand.count.sum())
