"""The transform tree a robot_state_publisher would publish for the arm, as plain data.

Every URDF joint gives one parent -> child transform: fixed joints once (``/tf_static``),
moving joints from the joint values of each ASTA (``/tf``). The world -> base_link transform
comes from where the platform stands (its GroundTruth pose, converted from USARSim's z-down
world to REP-103). Units: m; transforms are 4x4 matrices, quaternions (x, y, z, w).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from usar_arm.core.model import Joint, KinematicChain
from usar_arm.core.spatial import Array

FLIP_X = np.diag([1.0, -1.0, -1.0, 1.0])
"""USARSim's wire frame (x forward, y right, z down) <-> REP-103: a half turn about x."""


@dataclass(frozen=True)
class Edge:
    """One transform of the tree: ``child`` in ``parent`` (4x4, m)."""

    parent: str
    child: str
    matrix: Array


class TransformTree:
    """The arm's tree: static edges once, moving edges per joint configuration.

    Args:
        chain: the arm's kinematic chain (URDF joints and links).
        prefix: prepended to every frame name (``robot_state_publisher``'s frame_prefix).
        world: the name of the fixed frame above the root link.
    """

    def __init__(self, chain: KinematicChain, prefix: str = "", world: str = "world"):
        self.chain = chain
        self.prefix = prefix
        self.world = world
        self._moving = [j for j in chain.joints if j.actuated]
        self._fixed = [j for j in chain.joints if not j.actuated]
        names = chain.joint_names
        self._index = {j.name: names.index(j.name) for j in self._moving}

    def frame(self, name: str) -> str:
        """A link's frame name as published."""
        return f"{self.prefix}{name}"

    def static_edges(self, world_from_root: Array) -> list[Edge]:
        """world -> root and every fixed joint's transform."""
        edges = [Edge(self.world, self.frame(self.chain.root), np.asarray(world_from_root))]
        edges += [Edge(self.frame(j.parent), self.frame(j.child), j.origin.matrix())
                  for j in self._fixed]
        return edges

    def moving_edges(self, q: Array) -> list[Edge]:
        """Every moving joint's parent -> child transform at joint values ``q`` (chain
        order)."""
        return [Edge(self.frame(j.parent), self.frame(j.child), _joint_matrix(j, q[i]))
                for j, i in ((j, self._index[j.name]) for j in self._moving)]


def _joint_matrix(joint: Joint, value: float) -> Array:
    out: Array = joint.origin.matrix() @ joint.motion(float(value))
    return out


def world_from_platform(platform_wire: Array) -> Array:
    """base_link in a REP-103 world from the platform's z-down wire pose (4x4)."""
    out: Array = FLIP_X @ np.asarray(platform_wire, float) @ FLIP_X
    return out


def quaternion(rotation: Array) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a 3x3 rotation matrix, w >= 0 (Shepperd's method: stable everywhere)."""
    r = np.asarray(rotation, float)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        x, y, z, w = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s,
                      (r[1, 0] - r[0, 1]) / s, 0.25 * s)
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        x, y, z, w = (0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s,
                      (r[2, 1] - r[1, 2]) / s)
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        x, y, z, w = ((r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s,
                      (r[0, 2] - r[2, 0]) / s)
    else:
        s = 2.0 * np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        x, y, z, w = ((r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s,
                      (r[1, 0] - r[0, 1]) / s)
    sign = -1.0 if w < 0 else 1.0
    return (float(sign * x), float(sign * y), float(sign * z), float(sign * w))
