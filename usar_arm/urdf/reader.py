"""Read a URDF (with its SRDF and joint_limits.yaml) back into a KinematicChain.

Reads what :mod:`.writer` writes and what ROS tools commonly write for serial arms: links with a
cylinder (or no) collision geometry, revolute/prismatic/continuous/fixed joints with origin, axis
and limits. Other geometry types are kept as frames without geometry (and reported). Errors name
the element and what was expected.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from usar_arm.core.errors import FileFormatError
from usar_arm.core.model import (
    Cylinder,
    Joint,
    JointLimits,
    JointType,
    KinematicChain,
    Link,
    Origin,
)
from usar_arm.core.yamlio import loads_yaml

Pair = tuple[str, str]


def _floats(text: str | None, n: int, where: str, path: str, default: str) -> tuple[float, ...]:
    raw = (text if text is not None else default).split()
    try:
        values = tuple(float(v) for v in raw)
    except ValueError:
        raise FileFormatError(path, f"{where}: expected {n} numbers, got '{text}'") from None
    if len(values) != n:
        raise FileFormatError(path, f"{where}: expected {n} numbers, got '{text}'")
    return values


def _origin(el: ET.Element | None, where: str, path: str) -> Origin:
    if el is None:
        return Origin()
    xyz = _floats(el.get("xyz"), 3, f"{where} origin xyz", path, "0 0 0")
    rpy = _floats(el.get("rpy"), 3, f"{where} origin rpy", path, "0 0 0")
    return Origin(xyz, rpy)  # type: ignore[arg-type]


def parse_urdf(text: str, path: str = "<urdf>") -> tuple[KinematicChain, list[str]]:
    """The chain described by URDF text, and notes on anything it could not represent."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise FileFormatError(path, f"not valid XML: {exc}", line=exc.position[0]) from None
    if root.tag != "robot" or not root.get("name"):
        raise FileFormatError(path, "expected a <robot name=...> root element")
    notes: list[str] = []
    colours = {m.get("name"): m.find("color") for m in root.findall("material")}
    links = []
    for el in root.findall("link"):
        name = el.get("name") or ""
        geometry = None
        col = el.find("collision")
        if col is not None:
            cyl = col.find("geometry/cylinder")
            if cyl is None:
                notes.append(f"link {name}: only cylinder collision geometry is read; its "
                             "other geometry is ignored")
            else:
                try:
                    geometry = Cylinder(float(cyl.get("radius", "")), float(cyl.get("length", "")),
                                        _origin(col.find("origin"), f"link {name}", path))
                except ValueError:
                    raise FileFormatError(path, f"link {name}: cylinder needs numeric radius "
                                          "and length") from None
        colour, material = None, None
        mat = el.find("visual/material")
        if mat is not None:
            material = mat.get("name")
            c = mat.find("color")
            if c is None:
                c = colours.get(material)
            if c is not None:
                colour = _floats(c.get("rgba"), 4, f"link {name} colour", path, "1 1 1 1")
        links.append(Link(name, geometry, colour, material))  # type: ignore[arg-type]
    joints = []
    for el in root.findall("joint"):
        name = el.get("name") or ""
        kind = el.get("type", "")
        parent, child = el.find("parent"), el.find("child")
        if parent is None or child is None:
            raise FileFormatError(path, f"joint {name}: needs <parent> and <child>")
        jtype = {"revolute": JointType.REVOLUTE, "continuous": JointType.REVOLUTE,
                 "prismatic": JointType.PRISMATIC, "fixed": JointType.FIXED}.get(kind)
        if jtype is None:
            raise FileFormatError(path, f"joint {name}: type '{kind}' is not supported "
                                  "(revolute, continuous, prismatic, fixed)")
        axis_el = el.find("axis")
        axis = _floats((axis_el.get("xyz") if axis_el is not None else None),
                       3, f"joint {name} axis", path, "1 0 0")
        norm = float(np.linalg.norm(axis))
        limits = None
        if jtype is not JointType.FIXED:
            lim = el.find("limit")
            if kind == "continuous":
                lower, upper = -np.pi, np.pi
                notes.append(f"joint {name}: continuous, read as [-pi, pi]")
            elif lim is None:
                raise FileFormatError(path, f"joint {name}: a {kind} joint needs <limit>")
            else:
                lower, upper = float(lim.get("lower", "0")), float(lim.get("upper", "0"))
            limits = JointLimits(lower, upper,
                                 float(lim.get("velocity", "0")) if lim is not None else 1.0,
                                 float(lim.get("effort", "0")) if lim is not None else 0.0)
        joints.append(Joint(name, jtype, parent.get("link", ""), child.get("link", ""),
                            _origin(el.find("origin"), f"joint {name}", path),
                            tuple(a / norm for a in axis), limits))  # type: ignore[arg-type]
    frames = {role: role for role in ("base_link", "base", "flange", "tool0")
              if any(lk.name == role for lk in links)}
    chain = KinematicChain(root.get("name", ""), tuple(links), tuple(_order(joints, links)),
                           frames)
    return chain, notes


def _order(joints: list[Joint], links: list[Link]) -> list[Joint]:
    """Joints from the root outwards (breadth first)."""
    children = {j.child for j in joints}
    roots = [lk.name for lk in links if lk.name not in children]
    order: list[Joint] = []
    frontier = roots
    while frontier:
        nxt = []
        for name in frontier:
            for j in joints:
                if j.parent == name:
                    order.append(j)
                    nxt.append(j.child)
        frontier = nxt
    return order


def parse_srdf(text: str, path: str = "<srdf>") -> tuple[set[Pair], dict[str, dict[str, float]]]:
    """Disabled collision pairs and named group states of an SRDF."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise FileFormatError(path, f"not valid XML: {exc}", line=exc.position[0]) from None
    disabled = set()
    for el in root.findall("disable_collisions"):
        a, b = el.get("link1", ""), el.get("link2", "")
        disabled.add((a, b) if a <= b else (b, a))
    states = {}
    for el in root.findall("group_state"):
        states[el.get("name", "")] = {j.get("name", ""): float(j.get("value", "0"))
                                      for j in el.findall("joint")}
    return disabled, states


def apply_joint_limits_text(chain: KinematicChain, text: str, name: str = "<joint_limits>"
                            ) -> KinematicChain:
    """The chain with acceleration/jerk (and velocity) limits from a MoveIt joint_limits.yaml's
    text."""
    return apply_joint_limits_data(chain, loads_yaml(text, name))


def apply_joint_limits_data(chain: KinematicChain, data: object) -> KinematicChain:
    """:func:`apply_joint_limits_text` from the loaded YAML document."""
    table = (data or {}).get("joint_limits", {}) if isinstance(data, dict) else {}
    joints = []
    for j in chain.joints:
        entry = table.get(j.name)
        if entry is None or j.limits is None:
            joints.append(j)
            continue
        lim = j.limits
        acc = float(entry["max_acceleration"]) if entry.get("has_acceleration_limits") else None
        jerk = float(entry["max_jerk"]) if entry.get("has_jerk_limits") else None
        vel = float(entry["max_velocity"]) if entry.get("has_velocity_limits") else lim.velocity
        joints.append(Joint(j.name, j.type, j.parent, j.child, j.origin, j.axis,
                            JointLimits(lim.lower, lim.upper, vel, lim.effort, acc, jerk)))
    return KinematicChain(chain.name, chain.links, tuple(joints), chain.frames, chain.notes)
