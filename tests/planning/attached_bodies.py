"""Bodies to attach in the tests: one of each shape, sized to reach the arm's own links and the
scenes' obstacles from the KR60's gripper (m)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from usar_arm.core.spatial import transform_from_xyz_rpy
from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.robot import Robot, robot_from_files
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Sphere

KR60 = Path(__file__).resolve().parents[2] / "robots" / "generated" / "KR60.urdf"
TCP, GRIPPER = "KR60gripper_tcp", "KR60gripper"


def kr60() -> Robot:
    """The checked-in KR60 with its tool changer and vacuum gripper."""
    return robot_from_files(KR60)


def octahedron(radius: float) -> Mesh:
    """A closed triangle mesh: an octahedron of ``radius`` (m) about its origin."""
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
                 float) * radius
    f = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                  [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    return Mesh(v, f, "octahedron")


def body(kind: str, name: str = "part") -> AttachedBody:
    """A body of ``kind`` (box, cylinder, sphere, mesh) under the gripper's suction point,
    tilted so that its extent is not along the tool axis only."""
    shapes = {"box": Box((0.5, 0.12, 0.1)), "cylinder": CylinderShape(0.06, 0.6),
              "sphere": Sphere(0.15), "mesh": octahedron(0.25)}
    pose = transform_from_xyz_rpy((0.0, 0.05, 0.2), (0.3, 0.2, 0.1))
    return AttachedBody(name, TCP, shapes[kind], pose, (GRIPPER,))


def bar(length: float = 1.2, name: str = "bar") -> AttachedBody:
    """A long bar held across the gripper (along the TCP's x axis), centred on it."""
    pose = transform_from_xyz_rpy((0.0, 0.0, 0.05), (0.0, 0.0, 0.0))
    return AttachedBody(name, TCP, Box((length, 0.04, 0.04)), pose, (GRIPPER,))
