"""LIN motions: tool0 on a straight line (position linear, orientation by the shortest rotation).

The line is cut into steps (``step`` m of travel or ``rotation_step`` rad of turn, whichever gives
more); each pose is solved by IK from the previous configuration, so the arm stays on one branch.
A step where a joint would have to jump (a wrist flip, an elbow singularity), a pose out of reach
or beyond a limit, or a collision anywhere along the path stops the motion with an error that
names where on the line (fraction, tool position) and why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usar_arm.core.errors import IKError, LinBlockedError
from usar_arm.core.spatial import Array, exp_so3, log_so3, transform
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ik import IKSolver
from usar_arm.planning.ompl_adapter import edge_configurations, edge_steps


@dataclass(frozen=True)
class LinOptions:
    """Options of a LIN motion.

    Attributes:
        step: m of tool travel between IK points. rotation_step: rad of turn between points.
        max_joint_step: rad (or m); a larger change of any joint between neighbouring points
            is a branch flip and blocks the motion.
        resolution: joint resolution of the collision check between points.
        max_step: largest distance (m) any point of the robot moves between checked
            configurations (see :func:`~usar_arm.planning.ompl_adapter.edge_configurations`).
        rotation_length: m of path length counted per rad of turn (for the speed profile).
    """

    step: float = 0.005
    rotation_step: float = 0.01
    max_joint_step: float = 0.1
    resolution: float = 0.01
    max_step: float = 0.005
    rotation_length: float = 0.2


@dataclass(frozen=True)
class LinPath:
    """The joint configurations along the line and their path parameter s (m)."""

    q: Array
    s: Array
    length: float


def interpolate(a: Array, b: Array, fraction: float) -> Array:
    """The pose a fraction of the way from ``a`` to ``b`` (4x4s)."""
    rot = a[:3, :3] @ exp_so3(log_so3(a[:3, :3].T @ b[:3, :3]) * fraction)
    return transform(rot, a[:3, 3] + (b[:3, 3] - a[:3, 3]) * fraction)


def plan_lin(ik: IKSolver, world: CollisionWorld, start_q: Array, start_pose: Array,
             goal: Array, options: LinOptions = LinOptions()) -> LinPath:
    """Joint configurations moving tool0 from ``start_pose`` (at ``start_q``) to ``goal`` on a
    straight line.

    Raises:
        LinBlockedError: naming the first blocked point and the reason.
    """
    travel = float(np.linalg.norm(goal[:3, 3] - start_pose[:3, 3]))
    turn = float(np.linalg.norm(log_so3(start_pose[:3, :3].T @ goal[:3, :3])))
    steps = max(1, math.ceil(travel / options.step), math.ceil(turn / options.rotation_step))
    length = max(travel, options.rotation_length * turn, 1e-9)
    qs = [np.asarray(start_q, float)]
    for k in range(1, steps + 1):
        fraction = k / steps
        pose = interpolate(start_pose, goal, fraction)
        try:
            q = np.array(ik.solve(pose, qs[-1]).best.q)
        except IKError as exc:
            raise LinBlockedError(fraction, pose[:3, 3], f"no IK solution there: {exc}") from exc
        jump = np.abs(q - qs[-1])
        worst = int(np.argmax(jump))
        if jump[worst] > options.max_joint_step:
            raise LinBlockedError(
                fraction, pose[:3, 3],
                f"{ik.names[worst]} would jump {jump[worst]:.3f} rad between neighbouring "
                "points (a branch flip near a singularity); the line cannot be followed")
        qs.append(q)
    path = np.array(qs)
    levers = world.lever_arms()
    for k in range(len(path) - 1):
        checks = edge_steps(path[k], path[k + 1], options.resolution, levers, options.max_step)
        if world.segment_free(path[k], path[k + 1], checks):
            continue
        dense = edge_configurations(path[k], path[k + 1], options.resolution, levers,
                                    options.max_step)
        hits = world.in_collision_many(dense)
        if np.any(hits):
            bad = dense[int(np.argmax(hits))]
            pairs = world.contacts(bad)
            pose = ik.kin.frame_pose(bad, ik.frame)
            raise LinBlockedError(k / steps, pose[:3, 3], "collision: " + ", ".join(
                f"{a}–{b}" for a, b in pairs))
    return LinPath(path, np.linspace(0.0, length, len(path)), length)
