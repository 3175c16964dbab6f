"""Ground truth of the embedded simulator: where a robot's joints and tool0 really are.

Everything here comes from the simulator's own robot spec (:mod:`.robot_spec`) and its physics
state, never from a description learnt over the wire, so it can judge one. tool0 follows the
convention usar-arm's descriptions use (ROS-Industrial): it sits at the arm's Tip, its x axis is
the flange's, which points away from the last joint (turned from the base frame by the smallest
rotation), and it is that flange frame turned +90 degrees about y, so that its z axis points out
of the flange. Poses are in the robot's base_link: the actuator's frame with REP-103 axes
(x forward, y left, z up; USARSim's frame has y right and z down).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from usar_arm.core.spatial import FLIP_X, Array, invert, transform
from usar_arm.sim.robot_spec import ActuatorSpec, joint_frames, tip_pose
from usar_arm.usarsim.messages import ContactPair

_FLIP = transform(FLIP_X)
"""USARSim (z down) <-> REP-103 (z up): the same 4x4 both ways."""


@dataclass(frozen=True)
class EffectorTruth:
    """One of a robot's tools as the simulator has it (whatever EFF says).

    Attributes:
        name: the tool's ItemName (``KR60gripper``).
        attached: on a tool changer (its EFF lines are sent) or dropped.
        holder: the tool changer holding it (None when dropped).
        held: the name of the WorldController object its vacuum holds (None: nothing).
        pose: the tool's 4x4 pose in the robot's base_link (m, REP-103).
    """

    name: str
    attached: bool
    holder: str | None
    held: str | None
    pose: Array


@dataclass(frozen=True)
class Truth:
    """The simulator's state of one client's robot, read in one locked step.

    Attributes:
        key: the server's key of the client. peer: its address (``host:port``).
        sim_time: simulated time of the reading (s).
        joints: per actuator, the measured joint values (rad or m).
        tool0: per actuator, tool0's 4x4 pose in base_link (m).
        effectors: per tool the robot spawned with, its state (:class:`EffectorTruth`).
        contacts: the robot's contacts since it spawned (the latest 10,000 reported, then the
            ones not reported yet), as the contact extension names them.
    """

    key: str
    peer: str
    sim_time: float
    joints: dict[str, Array]
    tool0: dict[str, Array]
    effectors: dict[str, EffectorTruth] = field(default_factory=dict)
    contacts: tuple[ContactPair, ...] = ()


def _smallest_rotation_from_x(direction: Array) -> Array:
    """The rotation that takes the x axis to ``direction`` about their common normal."""
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    c = float(d[0])
    if c > 1.0 - 1e-12:
        return np.eye(3)
    if c < -1.0 + 1e-12:
        return np.diag([-1.0, -1.0, 1.0])
    v = np.array([0.0, -d[2], d[1]])  # x cross d
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + k + k @ k / (1.0 + c)


def tool0_in_tip(act: ActuatorSpec) -> Array:
    """tool0's pose (4x4) in the Tip frame of ``act`` (both with REP-103 axes), from the spec:
    constant, because both are carried rigidly by the last part."""
    zero = [0.0] * len(act.joints)
    tip: Array = _FLIP @ tip_pose(act, zero) @ _FLIP
    joints = [(_FLIP @ f)[:3, 3] for f in joint_frames(act, zero)]
    outward = tip[:3, 3] - joints[-1]
    if np.linalg.norm(outward) < 1e-6:  # a Tip on the last joint: along the last link
        outward = joints[-1] - joints[-2] if len(joints) > 1 else np.array([1.0, 0.0, 0.0])
    turn = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # +90 deg about y
    tool0 = transform(_smallest_rotation_from_x(outward) @ turn, tip[:3, 3].tolist())
    out: Array = invert(tip) @ tool0
    return out


def tool0_in_base(act: ActuatorSpec, platform_world: Array, tip_world: Array) -> Array:
    """tool0 (4x4, base_link) from the platform's and the Tip's world poses (USARSim frame)."""
    base: Array = platform_world @ act.mount()
    out: Array = _FLIP @ invert(base) @ tip_world @ _FLIP @ tool0_in_tip(act)
    return out


def in_base_link(platform_world: Array, pose_world: Array) -> Array:
    """A world pose (4x4, USARSim frame) in a robot's base_link (REP-103)."""
    out: Array = _FLIP @ invert(platform_world) @ pose_world @ _FLIP
    return out


def tool0_by_spec(act: ActuatorSpec, q: Array) -> Array:
    """tool0 (4x4, base_link) at joint values ``q`` by the spec's geometry alone."""
    out: Array = _FLIP @ tip_pose(act, [float(x) for x in q]) @ _FLIP @ tool0_in_tip(act)
    return out

