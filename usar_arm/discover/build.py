"""Build the KinematicChain of a learnt arm: REP-199 frames, joints, limits, two cylinders per link.

Each link with length gets a *body* cylinder, as thick as the link is long allows and trimmed
short of both joints so that neighbours do not touch across a joint housing, and a thin *core*
cylinder along the whole joint-to-joint segment, so that no obstacle passes between two links
through a joint (the body cylinders alone left the joints bare).

Link frames follow the 2012 generator's default "global axes" mode and ROS-Industrial practice:
every link frame is parallel to the actuator base frame at the zero pose (joint origins have
rpy = 0, only positions), and each joint's axis is its GEO axis expressed in that frame.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from usar_arm.core.model import (
    Collision,
    Cylinder,
    Joint,
    JointLimits,
    JointType,
    KinematicChain,
    Link,
    Origin,
)
from usar_arm.core.shapes import CylinderShape
from usar_arm.core.spatial import Array, matrix_to_rpy, rotation_onto, transform
from usar_arm.discover.frames import ArmFrames
from usar_arm.discover.limits import MotionLimits
from usar_arm.discover.naming import Naming
from usar_arm.discover.wire_arm import WireArm

KUKA_ORANGE = (246 / 255, 120 / 255, 40 / 255, 1.0)
BASE_GREY = (0.30, 0.30, 0.32, 1.0)
RADIUS_PER_LENGTH = 0.12
"""Cylinder radius as a fraction of the link's length..."""
RADIUS_RANGE = (0.03, 0.10)
"""...clamped to this range (m)."""
MIN_CYLINDER_LENGTH = 0.01
"""Links shorter than this (m, after trimming) get no geometry."""
CORE_RADIUS = 0.01
"""The core cylinder's radius (m): thin enough that links two apart, beside a short link
between them, do not touch where their bodies do not."""


def _vec(a: Array) -> tuple[float, float, float]:
    return (float(a[0]), float(a[1]), float(a[2]))


def link_cylinder(start: Array, end: Array, frame: Array | None = None) -> Cylinder | None:
    """A cylinder along the segment start -> end (m, link frame), kept clear of the joints.

    The radius grows with the segment's length; both ends are trimmed by the radius so the
    cylinder does not reach into the neighbouring links' joint housings. ``frame`` (4x4) maps the
    segment's coordinates into the link frame when they differ.
    """
    d = np.asarray(end, dtype=float) - np.asarray(start, dtype=float)
    length = float(np.linalg.norm(d))
    radius = min(RADIUS_RANGE[1], max(RADIUS_RANGE[0], RADIUS_PER_LENGTH * length))
    trimmed = length - 2 * radius
    if trimmed < max(MIN_CYLINDER_LENGTH, 0.4 * length):
        trimmed = length * 0.6
    if trimmed < MIN_CYLINDER_LENGTH:
        return None
    return Cylinder(radius, trimmed,
                    segment_origin(np.asarray(start, dtype=float), d, length, frame))


def segment_origin(start: Array, d: Array, length: float, frame: Array | None = None
                   ) -> Origin:
    """The pose of a cylinder centred on the segment start -> start + d (m, ``length`` its
    length), its z along it; ``frame`` (4x4) maps the segment's coordinates into the link's."""
    z = d / length
    ref = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(ref, z)
    x /= np.linalg.norm(x)
    rot = np.column_stack([x, np.cross(z, x), z])
    pose = transform(rot, start + d / 2)
    if frame is not None:
        pose = frame @ pose
    return Origin(_vec(pose[:3, 3]), matrix_to_rpy(pose[:3, :3]))


def link_core(start: Array, end: Array, frame: Array | None = None,
              skip: float = 0.0) -> Cylinder | None:
    """The thin core along the segment start -> end (m, link frame), less ``skip`` m at its
    start: it reaches both joints, so the links' shapes meet at every joint. None for a segment
    shorter than :data:`MIN_CYLINDER_LENGTH`."""
    d = np.asarray(end, dtype=float) - np.asarray(start, dtype=float)
    length = float(np.linalg.norm(d))
    if length < MIN_CYLINDER_LENGTH:
        return None
    begin = np.asarray(start, dtype=float) + d / length * skip
    d = d * (1 - skip / length)
    return Cylinder(CORE_RADIUS, length - skip, segment_origin(begin, d, length - skip, frame))


def link_collisions(start: Array, end: Array, frame: Array | None = None,
                    on_mount: bool = False) -> tuple[Collision, ...]:
    """A link's collision elements: its body cylinder and its core (either may be absent).
    ``on_mount``: ``start`` is the robot's foot (base_link's origin, on whatever it stands on),
    where there is no joint to close: the core starts where the body does, so that a floor
    under the robot is not a contact."""
    body = link_cylinder(start, end, frame)
    length = float(np.linalg.norm(np.asarray(end, dtype=float) - np.asarray(start, dtype=float)))
    skip = (length - body.length) / 2 if on_mount and body is not None else 0.0
    return tuple(Collision(CylinderShape(c.radius, c.length), c.origin)
                 for c in (body, link_core(start, end, frame, skip)) if c is not None)


def flange_rotation(direction: Array) -> Array:
    """Rotation whose x axis is ``direction`` (REP-199: flange x+ points away from the arm),
    turned from the base frame by the smallest rotation (a half turn about z for -x)."""
    return rotation_onto((1.0, 0.0, 0.0), direction, (0.0, 0.0, 1.0))


def build_chain(arm: WireArm, frames: ArmFrames, limits: Sequence[MotionLimits],
                naming: Naming, notes: Sequence[str] = ()) -> KinematicChain:
    """The robot description of a learnt arm, in ``frames``' convention (z-up or z-down)."""
    n = arm.dof
    p = frames.anchors
    mount = frames.mount
    links: list[Link] = []
    joints: list[Joint] = []
    base_shapes = link_collisions(np.zeros(3), p[0], on_mount=True)
    if naming.legacy:
        links.append(Link(naming.base_link))
        links.append(Link(naming.base, None, BASE_GREY, "base_grey", base_shapes))
        joints.append(Joint(naming.mount_joint(), JointType.FIXED, naming.base_link, naming.base,
                            Origin(_vec(mount[:3, 3]), matrix_to_rpy(mount[:3, :3]))))
        first_parent, first_origin = naming.base, transform(pos=p[0])
    else:
        base_shapes = link_collisions(np.zeros(3), p[0], frame=mount, on_mount=True)
        links.append(Link(naming.base_link, None, BASE_GREY, "base_grey", base_shapes))
        links.append(Link(naming.base))
        joints.append(Joint(naming.mount_joint(), JointType.FIXED, naming.base_link, naming.base,
                            Origin(_vec(mount[:3, 3]), matrix_to_rpy(mount[:3, :3]))))
        first_parent, first_origin = naming.base_link, mount @ transform(pos=p[0])
    # joint 1 at base_link's origin (a rail carriage on its mount): link 1 stands on the floor
    foot = bool(np.linalg.norm((mount @ transform(pos=p[0]))[:3, 3]) < 1e-9)
    for k in range(n):
        wj = arm.joints[k]
        end = p[k + 1] if k + 1 < n else frames.tip
        shapes = link_collisions(np.zeros(3), end - p[k], on_mount=k == 0 and foot)
        links.append(Link(naming.link(k + 1), None, KUKA_ORANGE, "kuka_orange", shapes))
        if k == 0:
            origin = Origin(_vec(first_origin[:3, 3]), matrix_to_rpy(first_origin[:3, :3]))
            parent = first_parent
        else:
            origin = Origin(_vec(p[k] - p[k - 1]))
            parent = naming.link(k)
        lim = limits[k]
        joints.append(Joint(
            naming.joint(k + 1),
            JointType.REVOLUTE if wj.joint_type == "Revolute" else JointType.PRISMATIC,
            parent, naming.link(k + 1), origin, _vec(frames.axes[k]),
            JointLimits(wj.min_value, wj.max_value, lim.velocity,
                        wj.max_torque if wj.max_torque is not None else 0.0,
                        lim.acceleration, lim.jerk)))
    outward = frames.tip - p[-1]
    if np.linalg.norm(outward) < 1e-6:
        outward = p[-1] - p[-2] if n > 1 else np.array([1.0, 0.0, 0.0])
    links.append(Link(naming.flange))
    joints.append(Joint(naming.flange_joint(n), JointType.FIXED, naming.link(n), naming.flange,
                        Origin(_vec(frames.tip - p[-1]),
                               matrix_to_rpy(flange_rotation(outward)))))
    links.append(Link(naming.tool0))
    joints.append(Joint(naming.tool0_joint(), JointType.FIXED, naming.flange, naming.tool0,
                        Origin((0.0, 0.0, 0.0), (0.0, np.pi / 2, 0.0))))
    frame_roles = {"base_link": naming.base_link, "base": naming.base,
                   "flange": naming.flange, "tool0": naming.tool0}
    if frames.tip_sensor is not None and arm.tip_sensor is not None:
        k = [j.link for j in arm.joints].index(arm.tip_sensor.link)
        rel = transform(pos=-p[k]) @ frames.tip_sensor
        name = arm.tip_sensor.name
        links.append(Link(name))
        joints.append(Joint(naming.sensor_joint(name), JointType.FIXED, naming.link(k + 1), name,
                            Origin(_vec(rel[:3, 3]), matrix_to_rpy(rel[:3, :3]))))
        frame_roles["tip_sensor"] = name
    return KinematicChain(arm.robot_name, tuple(links), tuple(joints), frame_roles, tuple(notes))
