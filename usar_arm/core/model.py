"""The data model: a serial arm as a tree of links and joints (numpy only).

A :class:`KinematicChain` is what discovery builds from the wire and what the URDF writer, the
planner and the executor share. Units are SI (m, rad, s, kg, N, N·m). Each joint rotates about (or
slides along) its ``axis``, expressed in the joint's frame, which sits at ``origin`` in the parent
link's frame; at q = 0 the child link's frame equals the joint frame.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from usar_arm.core.shapes import CylinderShape, Shape
from usar_arm.core.spatial import Array, Vector, exp_so3, transform, transform_from_xyz_rpy

Vec3 = tuple[float, float, float]


class JointType(str, Enum):
    """URDF joint types the project uses."""

    REVOLUTE = "revolute"
    PRISMATIC = "prismatic"
    FIXED = "fixed"


@dataclass(frozen=True)
class JointLimits:
    """Limits of one actuated joint.

    Attributes:
        lower, upper: position range (rad, or m for prismatic joints).
        velocity: maximum speed (rad/s or m/s), > 0.
        effort: maximum torque (N·m) or force (N); 0 when unknown (ROS-Industrial convention).
        acceleration: maximum acceleration (rad/s² or m/s²), None when unknown.
        jerk: maximum jerk (rad/s³ or m/s³), None when unknown.
    """

    lower: float
    upper: float
    velocity: float
    effort: float
    acceleration: float | None = None
    jerk: float | None = None

    @property
    def span(self) -> float:
        """upper - lower."""
        return self.upper - self.lower

    def contains(self, value: float, tol: float = 0.0) -> bool:
        """True when ``lower - tol <= value <= upper + tol``."""
        return self.lower - tol <= value <= self.upper + tol

    def clamp(self, value: float) -> float:
        """``value`` clamped into [lower, upper]."""
        return min(self.upper, max(self.lower, value))


@dataclass(frozen=True)
class Origin:
    """A pose relative to a parent frame: position (m) and fixed-axis roll, pitch, yaw (rad)."""

    xyz: Vec3 = (0.0, 0.0, 0.0)
    rpy: Vec3 = (0.0, 0.0, 0.0)

    def matrix(self) -> Array:
        """The 4x4 transform parent <- this frame."""
        return transform_from_xyz_rpy(self.xyz, self.rpy)


@dataclass(frozen=True)
class Cylinder:
    """A cylinder along the z axis of its ``origin`` frame, centred there (URDF convention).

    Attributes:
        radius: m. length: m. origin: pose in the owning link's frame.
    """

    radius: float
    length: float
    origin: Origin = Origin()


@dataclass(frozen=True)
class Collision:
    """One collision element of a link: a shape at ``origin`` in the link's frame (m).

    Attributes:
        shape: box, cylinder, sphere, capsule or triangle mesh (scaled, in metres).
        origin: the shape's pose in the owning link's frame.
    """

    shape: Shape
    origin: Origin = Origin()


RGBA = tuple[float, float, float, float]


@dataclass(frozen=True)
class Link:
    """A rigid body, or a pure frame when ``geometry`` is None.

    Attributes:
        name: unique link name.
        geometry: collision and visual shape, or None for frames (base, flange, tool0).
        color: RGBA in [0, 1] for the visual material.
        material: name of that material.
        collisions: the link's collision elements when they are not the one ``geometry``
            cylinder (meshes, boxes, spheres, capsules, several elements); empty otherwise.
    """

    name: str
    geometry: Cylinder | None = None
    color: RGBA | None = None
    material: str | None = None
    collisions: tuple[Collision, ...] = ()

    @property
    def elements(self) -> tuple[Collision, ...]:
        """Every collision element of the link: ``collisions``, or the ``geometry`` cylinder
        as one element, or none for a pure frame."""
        if self.collisions:
            return self.collisions
        if self.geometry is None:
            return ()
        g = self.geometry
        return (Collision(CylinderShape(g.radius, g.length), g.origin),)


@dataclass(frozen=True)
class Joint:
    """A joint between two links.

    Attributes:
        name: unique joint name.
        type: revolute, prismatic or fixed.
        parent, child: link names.
        origin: pose of the joint frame in the parent link frame.
        axis: unit rotation/translation axis in the joint frame (ignored for fixed joints).
        limits: None for fixed joints.
    """

    name: str
    type: JointType
    parent: str
    child: str
    origin: Origin = Origin()
    axis: Vec3 = (0.0, 0.0, 1.0)
    limits: JointLimits | None = None

    @property
    def actuated(self) -> bool:
        """True for revolute and prismatic joints."""
        return self.type is not JointType.FIXED

    def motion(self, q: float) -> Array:
        """The 4x4 transform joint frame <- child frame at joint value ``q``."""
        a = np.asarray(self.axis, dtype=float)
        if self.type is JointType.REVOLUTE:
            return transform(exp_so3(a * q))
        if self.type is JointType.PRISMATIC:
            return transform(pos=a * q)
        return np.eye(4)


@dataclass(frozen=True)
class KinematicChain:
    """A robot: links and joints forming a tree with one root, plus named reference frames.

    ``joints`` are ordered from the root outwards; actuated joints in that order define the
    configuration vector q.

    Attributes:
        name: robot name (URDF ``<robot name>``).
        links, joints: the tree.
        frames: role -> link name for the REP-199 frames: ``base_link``, ``base``, ``flange``,
            ``tool0`` (and any more a scheme defines).
        notes: provenance notes to write into generated files.
    """

    name: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    frames: dict[str, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    # ------------------------------------------------------------------ lookup
    def link(self, name: str) -> Link:
        """The link called ``name`` (KeyError lists the valid names)."""
        for lk in self.links:
            if lk.name == name:
                return lk
        raise KeyError(f"no link '{name}'; links: {', '.join(lk.name for lk in self.links)}")

    def joint(self, name: str) -> Joint:
        """The joint called ``name`` (KeyError lists the valid names)."""
        for jt in self.joints:
            if jt.name == name:
                return jt
        raise KeyError(f"no joint '{name}'; joints: {', '.join(j.name for j in self.joints)}")

    @property
    def root(self) -> str:
        """The one link that is no joint's child."""
        children = {j.child for j in self.joints}
        roots = [lk.name for lk in self.links if lk.name not in children]
        if len(roots) != 1:
            raise ValueError(f"expected exactly one root link, found {roots}")
        return roots[0]

    @property
    def actuated_joints(self) -> tuple[Joint, ...]:
        """Revolute and prismatic joints, in configuration order."""
        return tuple(j for j in self.joints if j.actuated)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the actuated joints, in configuration order."""
        return tuple(j.name for j in self.actuated_joints)

    @property
    def dof(self) -> int:
        """Number of actuated joints."""
        return len(self.actuated_joints)

    def limits(self) -> tuple[JointLimits, ...]:
        """Limits of the actuated joints, in configuration order."""
        return tuple(j.limits for j in self.actuated_joints if j.limits is not None)

    def lower(self) -> Array:
        """Lower position limits (rad or m)."""
        return np.array([lim.lower for lim in self.limits()])

    def upper(self) -> Array:
        """Upper position limits (rad or m)."""
        return np.array([lim.upper for lim in self.limits()])

    def path_to(self, link: str) -> list[Joint]:
        """Joints from the root to ``link``, in order."""
        by_child = {j.child: j for j in self.joints}
        self.link(link)
        path: list[Joint] = []
        cur = link
        while cur in by_child:
            jt = by_child[cur]
            path.append(jt)
            cur = jt.parent
        return path[::-1]

    # ------------------------------------------------------------------ kinematics
    def _walk(self, q: Vector) -> Iterator[tuple[Joint, Array, Array]]:
        """The forward-kinematics walk (the one of the data model): each joint in order with
        its world frame before its own motion and its child link's world pose, at ``q``."""
        values = dict(zip(self.joint_names, (float(v) for v in q), strict=True))
        poses: dict[str, Array] = {self.root: np.eye(4)}
        for jt in self.joints:
            frame = poses[jt.parent] @ jt.origin.matrix()
            poses[jt.child] = frame @ jt.motion(values.get(jt.name, 0.0))
            yield jt, frame, poses[jt.child]

    def link_poses(self, q: Vector) -> dict[str, Array]:
        """World (root-frame) 4x4 pose of every link at configuration ``q``.

        A straightforward reference implementation for checks and tests; the planner uses
        Pinocchio.
        """
        poses: dict[str, Array] = {self.root: np.eye(4)}
        poses.update((jt.child, pose) for jt, _, pose in self._walk(q))
        return poses

    def joint_frames(self, q: Vector) -> Iterator[tuple[Joint, Array]]:
        """Each joint with its world frame (before its own motion) at configuration ``q``."""
        for jt, frame, _ in self._walk(q):
            yield jt, frame

    def frame_pose(self, role_or_link: str, q: Vector) -> Array:
        """World pose of a REP-199 frame role (``tool0``) or a link name at ``q``."""
        name = self.frames.get(role_or_link, role_or_link)
        return self.link_poses(q)[name]
