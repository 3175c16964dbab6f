"""What the arm carries: :class:`AttachedBody`, an object fixed to a link at its grasp pose, and
:func:`carrying`, the chain with each carried object as one more link.

An attached body is an extra link of the chain, fixed to its parent link (Tesseract's way, and
MoveIt's AttachedCollisionObject in effect): every checker built from a chain and its kinematics
(the compiled verdicts, the exact FCL judge, IK's collision check, PTP and LIN, a path's
verification, the reach map) then moves it with that link, with no change of its own. The
links the body may touch (the gripper that holds it) and its parent link are added to the
disabled pairs, so that they are never checked against it.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from usar_arm.core.attach_errors import AttachError
from usar_arm.core.model import Collision, Joint, JointType, KinematicChain, Link, Origin
from usar_arm.core.shapes import Box, CylinderShape, ObstacleShape, Sphere
from usar_arm.core.spatial import Array, matrix_to_rpy

CARRIED_COLOUR = (0.95, 0.55, 0.1, 1.0)
"""RGBA of a carried object's visual (an orange part in the gripper)."""

Pair = tuple[str, str]


def _pair(a: str, b: str) -> Pair:
    return (a, b) if a <= b else (b, a)


@dataclass(frozen=True, eq=False)
class AttachedBody:
    """An object fixed to a robot link.

    Attributes:
        name: its name (a new link of that name carries it; a scene object's name when it was
            one). link: the link it is fixed to (``KR60gripper_tcp``). shape: its geometry (box,
            cylinder, sphere or mesh, m, in its own frame). pose: 4x4 pose of that frame in the
            link's frame (the grasp; m). touch_links: links it may touch (never checked against
            it; the parent link never is either).
    """

    name: str
    link: str
    shape: ObstacleShape
    pose: Array = field(default_factory=lambda: np.eye(4))
    touch_links: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        pose = np.array(self.pose, dtype=float)
        if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
            raise AttachError(self.name, f"the grasp pose must be a finite 4x4 transform, got "
                                         f"shape {pose.shape}")
        pose.setflags(write=False)
        object.__setattr__(self, "pose", pose)
        object.__setattr__(self, "touch_links", tuple(self.touch_links))

    def key(self) -> tuple[object, ...]:
        """A hashable value equal for bodies that are the same (name, link, shape, pose to the
        bit, touch links): what carrying robots are cached by."""
        return (self.name, self.link, shape_key(self.shape), self.pose.tobytes(),
                self.touch_links)

    def same_as(self, other: AttachedBody) -> bool:
        """True when ``other`` is the same body (:meth:`key`)."""
        return self.key() == other.key()


def shape_key(shape: ObstacleShape) -> tuple[object, ...]:
    """A hashable value of a shape (a mesh by a digest of its arrays)."""
    if isinstance(shape, Box):
        return ("box", tuple(float(v) for v in shape.size))
    if isinstance(shape, CylinderShape):
        return ("cylinder", float(shape.radius), float(shape.length))
    if isinstance(shape, Sphere):
        return ("sphere", float(shape.radius))
    digest = hashlib.sha256(np.ascontiguousarray(shape.vertices, float).tobytes()
                            + np.ascontiguousarray(shape.faces, np.int64).tobytes())
    return ("mesh", digest.hexdigest())


def body_link(body: AttachedBody) -> tuple[Link, Joint]:
    """The link that carries ``body`` (one collision element, its shape at the link's origin)
    and the fixed joint ``<link>-<name>`` that holds it at its grasp pose."""
    pose = body.pose
    xyz = (float(pose[0, 3]), float(pose[1, 3]), float(pose[2, 3]))
    origin = Origin(xyz, matrix_to_rpy(pose[:3, :3]))
    link = Link(body.name, color=CARRIED_COLOUR, material="carried",
                collisions=(Collision(body.shape, Origin()),))
    return link, Joint(f"{body.link}-{body.name}", JointType.FIXED, body.link, body.name,
                       origin)


def check_bodies(chain: KinematicChain, bodies: Sequence[AttachedBody]) -> None:
    """Raise :class:`AttachError` when a body names an unknown link (as parent or touch
    link), or a name that is already a link or another body's."""
    links = [lk.name for lk in chain.links]
    names = [b.name for b in bodies]
    for body in bodies:
        if body.link not in links and body.link not in names:
            raise AttachError(body.name, f"no link '{body.link}' to attach it to", links)
        if body.name in links:
            raise AttachError(body.name, "the name is already one of the robot's links", links)
        if names.count(body.name) > 1:
            raise AttachError(body.name, "two carried objects have that name", names)
        unknown = [t for t in body.touch_links if t not in links and t not in names]
        if unknown:
            raise AttachError(body.name, f"no link '{unknown[0]}' among its touch links",
                              links)
    for k, body in enumerate(bodies):  # a body on a body: its parent must come first
        if body.link in names[k:]:
            raise AttachError(body.name, f"'{body.link}' is carried after it (list a body "
                                         "before the bodies fixed to it)", names[:k])


def carrying(chain: KinematicChain, disabled: Iterable[Pair],
             bodies: Sequence[AttachedBody]) -> tuple[KinematicChain, set[Pair]]:
    """The chain with each body as a link fixed to its parent, and the disabled pairs with
    (body, parent) and (body, touch link) added.

    Raises:
        AttachError: an unknown link, a name clash (:func:`check_bodies`).
    """
    check_bodies(chain, bodies)
    links, joints = list(chain.links), list(chain.joints)
    pairs = {_pair(a, b) for a, b in disabled}
    for body in bodies:
        link, joint = body_link(body)
        links.append(link)
        joints.append(joint)
        pairs.add(_pair(body.name, body.link))
        pairs.update(_pair(body.name, t) for t in body.touch_links)
    notes = (*chain.notes, *(f"carrying '{b.name}' on {b.link}" for b in bodies))
    return KinematicChain(chain.name, tuple(links), tuple(joints), dict(chain.frames),
                          notes), pairs
