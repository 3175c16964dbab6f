"""The frames of a learnt arm's effectors: each tool's origin and its tip, on the link it rides.

An effector's GEO (:mod:`.effectors`) gives its origin from its mount (an arm link's joint
anchor, or another effector's origin) and its rotation relative to the robot, both in world
axes at the spawn pose; the robot's start pose (GETSTARTPOSES) turns world axes into the
platform's, the actuator's mount into the actuator base frame the arm's joint frames live in
(:class:`.frames.ArmFrames`). Rotations within the wire's rounding of a canonical rotation are
snapped, as the joint frames are. The tip is the TipOffset in the effector's own frame.

Everything is computed in USARSim's z-down frame and converted once, by
:func:`zup_effector_frames`, as :func:`.frames.to_frame` does for the joints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from usar_arm.core.spatial import FLIP_X, Array, exp_so3, invert, rpy_to_matrix, transform
from usar_arm.discover.effectors import WireEffector
from usar_arm.discover.frames import SNAP_FACTOR, ArmFrames, Snap, nearest_rotation

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class EffectorFrame:
    """Where one effector sits, in the actuator base frame (4x4 poses, m).

    Attributes:
        effector: what the wire said. link: the arm link (1-based USARSim link) whose part
            carries it, directly or through the effectors it rides on; 0 for the actuator base.
        parent: the name of what it rides on (the actuator, or an effector).
        pose: its origin and rotation. tip: its tip (the pose moved by its TipOffset).
    """

    effector: WireEffector
    link: int
    parent: str
    pose: Array
    tip: Array


def link_frames_at(frames: ArmFrames, q: tuple[float, ...], prismatic: tuple[bool, ...]
                   ) -> list[Array]:
    """Each joint's link frame (4x4, in ``frames``' actuator base frame) at joint values ``q``:
    at the zero pose the frame at the joint's anchor, parallel to the base frame, as the
    description's link frames are; moved by the joints up to it."""
    out, chain = [], np.eye(4)
    for anchor, axis, value, slide in zip(frames.anchors, frames.axes, q, prismatic,
                                          strict=True):
        if slide:
            step = transform(pos=axis * value)
        else:
            rot = exp_so3(axis * value)
            step = transform(rot, anchor - rot @ anchor)
        chain = chain @ step
        out.append(chain @ transform(pos=anchor))
    return out


def effector_frames(frames: ArmFrames, effectors: tuple[WireEffector, ...],
                    joint_links: tuple[int, ...], actuator: str,
                    spawn_rotation: Vec3 = (0.0, 0.0, 0.0),
                    joints: tuple[float, ...] | None = None,
                    prismatic: tuple[bool, ...] | None = None
                    ) -> tuple[tuple[EffectorFrame, ...], tuple[Snap, ...]]:
    """The frames (z-down, like ``frames``; at the zero pose) of ``effectors`` (mounted in
    order, each after the one it rides on), and the rotations snapped.

    Args:
        frames: the arm's joint frames in the z-down actuator base frame.
        joint_links: the USARSim link of each joint, in chain order.
        actuator: the arm's name (an effector whose Mount is it rides on the arm).
        spawn_rotation: the robot's roll, pitch, yaw at its spawn (rad): GEO's world axes are
            turned into the platform's by it.
        joints, prismatic: the joint values (rad or m) the arm stood at while the GEO lines
            were asked, and which joints slide: GEO measures in world axes at that pose (a
            spawned arm sags), so each effector is taken back to its mount link's frame there
            and placed on it at the zero pose. None: the zero pose. Over a wire that prints
            locations in steps (UDK: 0.01 m) the offset from the mount, which the sag moves by
            far less than a step, is put back on the printed grid, so the same lines give the
            same description whatever the arm's sag when they were asked.
    """
    if frames.frame != "z-down":
        raise ValueError(f"effector frames are computed from z-down frames, got {frames.frame}")
    n = len(frames.anchors)
    at_q = link_frames_at(frames, joints or (0.0,) * n, prismatic or (False,) * n)
    at_zero = [transform(pos=p) for p in frames.anchors]
    to_platform = rpy_to_matrix(spawn_rotation).T
    to_actuator = frames.mount[:3, :3].T
    done: dict[str, tuple[EffectorFrame, Array]] = {}
    out: list[EffectorFrame] = []
    snaps: list[Snap] = []
    for e in effectors:
        offset = to_actuator @ to_platform @ np.asarray(e.location, dtype=float)
        rot = to_actuator @ rpy_to_matrix(e.orientation)
        if e.mount.lower() == actuator.lower():
            link = e.mount_link or 0
            k = joint_links.index(link) if link else -1
            here, zero = (at_q[k], at_zero[k]) if link else (np.eye(4), np.eye(4))
            parent = actuator
        else:
            below, below_q = done[e.mount.lower()]
            link, parent, here, zero = below.link, below.effector.name, below_q, below.pose
        pose_q = transform(rot, here[:3, 3] + offset)
        pose = zero @ invert(here) @ pose_q
        if e.location_resolution > 0:  # the sag moved it less than the print step: back on it
            step = e.location_resolution
            pose[:3, 3] = zero[:3, 3] + np.round((pose[:3, 3] - zero[:3, 3]) / step) * step
        canon, dev = nearest_rotation(pose[:3, :3])
        if 0 < dev <= SNAP_FACTOR * e.orientation_resolution:
            snaps.append(Snap(f"{e.type} {e.name} frame", dev, tuple(canon.ravel())))
            pose[:3, :3] = canon
        frame = EffectorFrame(e, link, parent, pose, pose @ transform(pos=e.tip))
        done[e.name.lower()] = (frame, pose_q)
        out.append(frame)
    return tuple(out), tuple(snaps)


def zup_effector_frames(frames: tuple[EffectorFrame, ...]) -> tuple[EffectorFrame, ...]:
    """The same frames in REP-103's z-up convention ((x, y, z) -> (x, -y, -z), R -> Rx(pi) R
    Rx(pi)): a z-down effector frame's local +z (a suction or approach axis) becomes the z-up
    frame's local -z."""
    flip = transform(FLIP_X)
    return tuple(EffectorFrame(f.effector, f.link, f.parent, flip @ f.pose @ flip,
                               flip @ f.tip @ flip) for f in frames)
