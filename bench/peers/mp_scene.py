"""mplib obstacle set-up shared by the mplib runners (runs in the mplib venv).

Obstacles (see README-peers.md): box / cylinder / sphere / mesh (``file``, ``scale``; loaded
with ``fcl.load_mesh_as_BVH``), pose ``xyz`` + ``quat_wxyz`` in base_link, optional ``allow``
(robot links allowed to touch it: set in the planning world's allowed-collision matrix).
"""

import numpy as np
from mplib import Pose
from mplib.collision_detection import fcl


def shape(ob):
    if ob["type"] == "box":
        return fcl.Box(np.array(ob["size"], float))
    if ob["type"] == "cylinder":
        return fcl.Cylinder(ob["radius"], ob["length"])
    if ob["type"] == "sphere":
        return fcl.Sphere(ob["radius"])
    if ob["type"] == "mesh":
        return fcl.load_mesh_as_BVH(ob["file"], np.full(3, float(ob.get("scale", 1.0))))
    raise ValueError(f"unknown obstacle type {ob['type']!r}")


class Obstacles:
    """The obstacles of one scene at a time in a Planner's planning world."""

    def __init__(self, planner, scenes: dict):
        self.planner = planner
        self.scenes = scenes
        self.present: list[str] = []

    def enter(self, name: str) -> None:
        world = self.planner.planning_world
        while self.present:
            world.remove_object(self.present.pop())
        acm = world.get_allowed_collision_matrix()
        for i, ob in enumerate(self.scenes[name]):
            key = f"{name}/{ob.get('name', i)}"
            pose = Pose(
                p=np.array(ob["xyz"], float),
                q=np.array(ob.get("quat_wxyz", [1, 0, 0, 0]), float),
            )
            world.add_object(key, fcl.CollisionObject(shape(ob), pose))
            for link in ob.get("allow", []):
                acm.set_entry(key, link, True)
            self.present.append(key)
