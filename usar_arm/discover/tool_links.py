"""A learnt arm's effectors as links of its description: the tool changer, the tool, its TCP.

Each effector becomes a link fixed to what it rides on (``<name>_mount``, as the 2012 generator
named the KR60's ``toolchange_mount``): an arm link, or the effector below it. A tool with a tip
(a vacuum gripper's suction point) also gets a TCP frame ``<name>_tcp`` at the tip, its z axis
pointing out of the tool along the suction axis (ROS-Industrial's tool0 convention), and a
collision body: the wire gives no tool geometry, so the body is a cylinder of
:data:`TOOL_RADIUS` (a conservative default, announced as such in the notes and discovery.json)
from the tool's origin to its tip, lengthened by the Tip's print step (UDK prints 0.18 for the
KR60 vacuum's 0.183 m). A tool changer gets no body: UDK's is a phantom part without
collision.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from usar_arm.core.model import Collision, Joint, JointType, KinematicChain, Link, Origin
from usar_arm.core.shapes import CylinderShape
from usar_arm.core.spatial import Array, invert, matrix_to_rpy, rotation_onto, transform
from usar_arm.discover.build import segment_origin
from usar_arm.discover.tool_frames import EffectorFrame

TOOL_RADIUS = 0.09
"""Radius (m) of a tool's collision cylinder: the wire carries no tool geometry; 9 cm holds a
hand-sized tool (UDK's VacuumGripper mesh is 13 x 9 cm across, its corners 8.4 cm off its
axis)."""
TOOL_GREY = (0.55, 0.57, 0.60, 1.0)
MIN_TIP = 1e-3
"""A tip shorter than this (m) is no tip: the tool gets neither a body nor a TCP."""


@dataclass(frozen=True)
class ToolLinks:
    """The links and joints of the effectors, and the frame roles they fill.

    Attributes:
        links, joints: to add to the arm's chain, each joint after its parent exists.
        roles: ``tool_changer``, ``tool`` and ``tcp`` -> link name (the first of each).
        notes: what the description should say about them (the defaults used).
    """

    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    roles: dict[str, str]
    notes: tuple[str, ...]


def _origin(t: Array) -> Origin:
    return Origin((float(t[0, 3]), float(t[1, 3]), float(t[2, 3])), matrix_to_rpy(t[:3, :3]))


def z_along(direction: Array) -> Array:
    """The smallest rotation taking z onto ``direction`` (3x3; a half turn about x for -z)."""
    return rotation_onto((0.0, 0.0, 1.0), direction, (1.0, 0.0, 0.0))


def tool_links(frames: tuple[EffectorFrame, ...], link_frames: dict[int, tuple[str, Array]]
               ) -> ToolLinks:
    """The effectors' links, in the output frame convention of ``frames``.

    Args:
        frames: the effectors' frames in the actuator base frame (4x4, m), mounted in order.
        link_frames: USARSim link (1-based; 0: the actuator base) -> the description's link
            name and its frame in the actuator base frame at the zero pose (4x4).
    """
    links: list[Link] = []
    joints: list[Joint] = []
    roles: dict[str, str] = {}
    notes: list[str] = []
    placed: dict[str, Array] = {}
    for f in frames:
        e = f.effector
        if f.parent.lower() in placed:
            parent, parent_pose = f.parent, placed[f.parent.lower()]
        else:
            parent, parent_pose = link_frames[f.link]
        rel = invert(parent_pose) @ f.pose
        placed[e.name.lower()] = f.pose
        tip_local = (invert(f.pose) @ f.tip)[:3, 3]
        length = float(np.linalg.norm(tip_local))
        body: tuple[Collision, ...] = ()
        if not e.is_tool_changer and length >= MIN_TIP:
            reach = length + e.tip_resolution  # the true tip may lie half a print step further
            body = (Collision(CylinderShape(TOOL_RADIUS, reach),
                              segment_origin(np.zeros(3), tip_local * reach / length, reach)),)
            notes.append(f"{e.name}: the wire gives no tool geometry; its collision body is a "
                         f"cylinder of the default radius {TOOL_RADIUS:g} m from its origin to "
                         f"its tip ({length:.3f} m, plus the Tip's print step "
                         f"{e.tip_resolution:g} m).")
        links.append(Link(e.name, None, TOOL_GREY if body else None,
                          "tool_grey" if body else None, body))
        joints.append(Joint(f"{e.name}_mount", JointType.FIXED, parent, e.name, _origin(rel)))
        roles.setdefault("tool_changer" if e.is_tool_changer else "tool", e.name)
        if not e.is_tool_changer and length >= MIN_TIP:
            tcp = f"{e.name}_tcp"
            links.append(Link(tcp))
            joints.append(Joint(f"{e.name}-{tcp}", JointType.FIXED, e.name, tcp,
                                _origin(transform(z_along(tip_local), tip_local))))
            roles.setdefault("tcp", tcp)
    return ToolLinks(tuple(links), tuple(joints), roles, tuple(notes))


def with_tools(chain: KinematicChain, tools: ToolLinks) -> KinematicChain:
    """``chain`` with the effectors' links, joints and frame roles added (and their notes)."""
    return replace(chain, links=chain.links + tools.links, joints=chain.joints + tools.joints,
                   frames={**chain.frames, **tools.roles}, notes=chain.notes + tools.notes)


def effector_json(frame: EffectorFrame, chain: KinematicChain) -> dict[str, Any]:
    """What discovery.json records of one effector: what the wire said (its names, opcodes and
    tolerances, its GEO in the wire's terms) and where it went in the description (its link,
    the link it is fixed to, its TCP frame or None)."""
    e = frame.effector
    parent = next(j.parent for j in chain.joints if j.child == e.name)
    tcp = f"{e.name}_tcp"
    return {"name": e.name, "type": e.type, "mount": e.mount, "mount_link": e.mount_link,
            "link": e.name, "parent_link": parent,
            "tcp": tcp if any(lk.name == tcp for lk in chain.links) else None,
            "opcodes": list(e.opcodes), "position_tolerance_m": e.position_tolerance,
            "angle_tolerance_rad": e.angle_tolerance, "wire_location_m": list(e.location),
            "wire_orientation_rad": list(e.orientation), "wire_tip_m": list(e.tip),
            "resolution": {"location_m": e.location_resolution,
                           "orientation_rad": e.orientation_resolution,
                           "tip_m": e.tip_resolution}}
