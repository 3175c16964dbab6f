"""What a workspace job needs of an arm, and how a worker gets one.

The workspace layer never builds a robot itself (that is the facades' job,
:func:`usar_arm.planning.robot.robot_from_texts`): a job carries a picklable ``build`` callable (a
module-level function and the description's text, by value) that each worker calls once.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from typing import Protocol

import numpy as np

from usar_arm.core.model import KinematicChain
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ik import IKOptions, IKSolver
from usar_arm.planning.scene import (
    Box,
    CylinderShape,
    Mesh,
    Scene,
    Sphere,
)


class ArmModel(Protocol):
    """An arm ready for IK and collision checking (:class:`usar_arm.planning.robot.Robot` is
    one)."""

    chain: KinematicChain

    def ik_solver(self, options: IKOptions | None = None, frame: str = "tool0") -> IKSolver:
        """An IK solver of ``frame``."""
        ...

    def collision_world(self, scene: Scene = ..., padding: float = 0.0) -> CollisionWorld:
        """A collision world of the arm in ``scene``."""
        ...


ArmBuilder = Callable[[], ArmModel]
"""Builds the arm in a worker (picklable: e.g. ``functools.partial`` of a module-level
function and text)."""


def scene_fingerprint(scene: Scene) -> str:
    """The scene as stable text (shapes, sizes, poses; meshes by a digest of their arrays), for
    a job's key."""
    items = []
    for o in scene.objects:
        s = o.shape
        if isinstance(s, Box):
            shape: list = ["box", list(s.size)]
        elif isinstance(s, CylinderShape):
            shape = ["cylinder", s.radius, s.length]
        elif isinstance(s, Sphere):
            shape = ["sphere", s.radius]
        else:
            assert isinstance(s, Mesh)
            h = hashlib.sha256(np.ascontiguousarray(s.vertices, float).tobytes()
                               + np.ascontiguousarray(s.faces, np.int64).tobytes())
            shape = ["mesh", h.hexdigest()[:16]]
        items.append([o.name, shape, np.round(o.pose, 12).tolist(), list(o.allow)])
    return json.dumps([scene.name, items])
