"""The reachability map of an arm carrying a body: no voxel gains, some lose (poses where only
the body collides), every witness is free with the body by brute force, and a worker process
rebuilds the carrying arm from the description's text."""

from __future__ import annotations

import pickle

import numpy as np

from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.scene import Sphere
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace import jobs
from usar_arm.workspace.reach import ReachSettings

from .attached_bodies import GRIPPER, TCP, kr60


def test_the_reach_map_honours_the_carried_body() -> None:
    arm = kr60()
    grasp = np.eye(4)
    grasp[2, 3] = 0.3
    carried = arm.carrying([AttachedBody("ball", TCP, Sphere(0.3), grasp, (GRIPPER,))])
    scene = load_scene("table")
    settings = ReachSettings(resolution=0.3, orientations=12, edges=False)
    bare = jobs.reach_map(arm, scene, settings, jobs.backend_for(0)).map
    held = jobs.reach_map(carried, scene, settings, jobs.backend_for(0)).map
    assert np.all(held.index <= bare.index)
    assert held.index.sum() < 0.95 * bare.index.sum()
    world = carried.collision_world(scene)
    witnesses = held.best_q[held.index > 0]
    assert len(witnesses) > 20
    assert not any(world.contacts_brute_force(q) for q in witnesses)
    rebuilt = pickle.loads(pickle.dumps(jobs.arm_builder(carried)))()
    assert [b.key() for b in rebuilt.carried] == [b.key() for b in carried.carried]
    assert jobs.description_text(rebuilt) == jobs.description_text(carried) != \
        jobs.description_text(arm)
