"""Tesseract set-up shared by the Tesseract runners (runs in the tesseract venv).

The robot comes from the Tesseract config folder ``usar-arm tesseract-config`` wrote (the
problem's "tesseract" key: URDF, SRDF with its kinematics and contact manager plugin configs);
obstacles from the problem's scenes are added as links fixed to base_link (or ``parent``)
(``AddLinkCommand``), meshes read by Tesseract itself (``createMeshFromPath``), ``allow`` pairs
put into the allowed collision matrix; the obstacles of the previous scene are removed
(``RemoveLinkCommand``) first.
"""

import os
from pathlib import Path

import numpy as np
import peerio


def load(spec: dict):
    """(environment, the manipulator group's joint names); the folder is found by Tesseract's
    own resource locator (TESSERACT_RESOURCE_PATH, as the folder's README says)."""
    folder = Path(spec["tesseract"])
    os.environ["TESSERACT_RESOURCE_PATH"] = str(folder)
    from tesseract_robotics import tesseract_common as common
    from tesseract_robotics import tesseract_environment as te

    robot = Path(spec["urdf"]).stem
    env = te.Environment()
    if not env.init(common.FilesystemPath(str(folder / f"{robot}.urdf")),
                    common.FilesystemPath(str(folder / f"{robot}.srdf")),
                    common.GeneralResourceLocator()):
        raise SystemExit(f"Tesseract could not load {folder}")
    group = spec.get("tesseract_group") or spec.get("group", "manipulator")
    return env, list(env.getKinematicGroup(group).getJointNames())


def _geometry(item: dict):
    from tesseract_robotics import tesseract_geometry as geo

    kind = item["type"]
    if kind == "box":
        return geo.Box(*item["size"])
    if kind == "cylinder":
        return geo.Cylinder(item["radius"], item["length"])
    if kind == "sphere":
        return geo.Sphere(item["radius"])
    if kind == "mesh":
        scale = float(item.get("scale", 1.0))
        meshes = geo.createMeshFromPath(item["file"], np.array([scale, scale, scale]))
        return meshes[0]
    raise ValueError(f"unknown obstacle type {kind!r}")


class Obstacles:
    """Swaps the environment's obstacles scene by scene (``enter(name)``, untimed)."""

    def __init__(self, env, scenes: dict, on_change=None, parent: str = "base_link"):
        self.env, self.scenes, self.on_change, self.current = env, scenes, on_change, []
        self.parent = parent  # the link the scene's poses are given in

    def enter(self, name: str) -> None:
        from tesseract_robotics import tesseract_common as common
        from tesseract_robotics import tesseract_environment as te
        from tesseract_robotics import tesseract_scene_graph as sg

        for link in self.current:
            self.env.applyCommand(te.RemoveLinkCommand(link))
        self.current = []
        acm = common.AllowedCollisionMatrix()
        for item in self.scenes.get(name, []):
            link = sg.Link(item["name"])
            collision = sg.Collision()
            collision.geometry = _geometry(item)
            link.collision.push_back(collision)
            joint = sg.Joint(f"{item['name']}_joint")
            joint.parent_link_name, joint.child_link_name = self.parent, item["name"]
            joint.type = sg.JointType_FIXED
            pose = peerio.pose_matrix(item["xyz"], item.get("quat_wxyz", [1, 0, 0, 0]))
            joint.parent_to_joint_origin_transform = common.Isometry3d(pose)
            self.env.applyCommand(te.AddLinkCommand(link, joint))
            self.current.append(item["name"])
            for other in item.get("allow", []):
                acm.addAllowedCollision(item["name"], other, "allowed by the scene")
        self.env.applyCommand(te.ModifyAllowedCollisionsCommand(
            acm, te.ModifyAllowedCollisionsType_ADD))
        if self.on_change is not None:
            self.on_change(name)
