"""Read any URDF into a :class:`~usar_arm.core.model.KinematicChain`, with yourdfpy (the one
module that imports it).

The chain is the URDF's whole tree: revolute, continuous (read as revolute on [-pi, pi]),
prismatic and fixed joints, with their mimic relations kept beside it (:class:`UrdfTree`); the
planning group is cut from it by :mod:`.group`. A link whose one collision element is a
cylinder keeps it as its ``geometry`` (what usar-arm writes reads back to the same chain); any
other collision geometry (meshes, boxes, spheres, capsules, several elements) becomes its
``collisions``, meshes loaded and scaled (:mod:`.meshes`), resources resolved as ROS tools do
(:mod:`.packages`). yourdfpy keeps origins as 4x4 matrices; their xyz/rpy text is read from the
same document so a written description reads back to the very numbers it holds.
"""

from __future__ import annotations

import io
import logging
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from usar_arm.core.errors import FileFormatError, RobotStructureError
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
from usar_arm.core.shapes import Box, Capsule, CylinderShape, Shape, Sphere
from usar_arm.urdf.packages import PackagePaths

if TYPE_CHECKING:
    import yourdfpy


def _yourdfpy() -> Any:
    """yourdfpy, imported on first use: it brings trimesh, which an arm learnt over the wire
    (or a command that reads no URDF) never needs."""
    import yourdfpy

    logging.getLogger("yourdfpy").setLevel(logging.ERROR)  # its own warnings repeat ours
    return yourdfpy

_TYPES = {"revolute": JointType.REVOLUTE, "continuous": JointType.REVOLUTE,
          "prismatic": JointType.PRISMATIC, "fixed": JointType.FIXED}


@dataclass(frozen=True)
class Mimic:
    """A joint that follows another: q = multiplier * q(joint) + offset (rad or m)."""

    joint: str
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class ReadOptions:
    """How to read a URDF's resources.

    Attributes:
        packages: where ``package://`` resources are. convex_hull: replace every collision mesh
            by its convex hull (the user's choice; reported). meshes: load collision meshes
            (False: a link's meshes are left out, for kinematics only).
    """

    packages: PackagePaths = field(default_factory=PackagePaths)
    convex_hull: bool = False
    meshes: bool = True


@dataclass(frozen=True)
class UrdfTree:
    """A URDF as read: the whole tree, its mimic joints, and notes on what was approximated."""

    chain: KinematicChain
    mimic: dict[str, Mimic]
    notes: tuple[str, ...]


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


def _document(text: str, path: str) -> ET.Element:
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise FileFormatError(path, f"not valid XML: {exc}", line=exc.position[0]) from None
    if root.tag != "robot" or not root.get("name"):
        raise FileFormatError(path, "expected a <robot name=...> root element")
    return root


def _without_capsules(root: ET.Element, text: str) -> bytes:
    """The document for yourdfpy, which rejects ``<capsule>`` (an extension Drake and newer
    urdfdom read): each becomes a cylinder there, and :func:`_shape` reads the capsule."""
    capsules = root.findall(".//collision/geometry/capsule") + root.findall(
        ".//visual/geometry/capsule")
    if not capsules:
        return text.encode()
    copy = ET.fromstring(text)
    for el in copy.iter():
        for child in list(el):
            if child.tag == "capsule":
                child.tag = "cylinder"
    return ET.tostring(copy)


def parse_urdf(text: str, path: str = "<urdf>") -> tuple[KinematicChain, list[str]]:
    """The chain of URDF text without its meshes (kinematics, cylinders, primitives), and
    notes on anything approximated."""
    tree = read_urdf(text, path, ReadOptions(meshes=False))
    return tree.chain, list(tree.notes)


def read_urdf(text: str, path: str = "<urdf>", options: ReadOptions | None = None) -> UrdfTree:
    """The whole tree of URDF text (``path``: its file, for resources and messages).

    Raises:
        FileFormatError: not a URDF, or a joint without what its type needs.
        RobotStructureError: a floating or planar joint (no fixed base to plan from).
        FileFormatError: also for a collision mesh that cannot be found or read (link and path
            named).
    """
    options = options or ReadOptions()
    root = _document(text, path)
    try:
        robot = _yourdfpy().URDF.load(io.BytesIO(_without_capsules(root, text)),
                                   build_scene_graph=False,
                                   build_collision_scene_graph=False, load_meshes=False,
                                   load_collision_meshes=False).robot
    except Exception as exc:  # yourdfpy/lxml raise many types on a bad document
        raise FileFormatError(path, f"yourdfpy cannot read it: {exc}") from None
    notes: list[str] = []
    colours = {m.name: m.color for m in robot.materials if m.color is not None}
    elements = {el.get("name", ""): el for el in root.findall("link")}
    links = [_link(lk, elements[lk.name], colours, path, options, notes) for lk in robot.links]
    origins = {el.get("name", ""): el.find("origin") for el in root.findall("joint")}
    joints, mimic = [], {}
    for j in robot.joints:
        joints.append(_joint(j, origins.get(j.name), path, notes))
        if j.mimic is not None:
            mimic[j.name] = Mimic(j.mimic.joint, 1.0 if j.mimic.multiplier is None
                                  else float(j.mimic.multiplier),
                                  float(j.mimic.offset or 0.0))
    frames = {role: role for role in ("base_link", "base", "flange", "tool0")
              if any(lk.name == role for lk in links)}
    chain = KinematicChain(robot.name, tuple(links), tuple(_order(joints, links)), frames)
    return UrdfTree(chain, mimic, tuple(notes))


def _link(lk: yourdfpy.Link, el: ET.Element, colours: dict, path: str, options: ReadOptions,
          notes: list[str]) -> Link:
    """One link: its collision elements, colour and material."""
    xml = el.findall("collision")
    items = [(_origin(x.find("origin"), f"link {lk.name}", path), c.geometry, x)
             for c, x in zip(lk.collisions, xml, strict=True)]
    geometry, collisions = None, []
    for origin, g, x in items:
        shape = _shape(lk.name, g, x, path, options)
        if shape is None:
            notes.append(f"link {lk.name}: a collision element without a shape is ignored")
        elif isinstance(shape, CylinderShape) and len(items) == 1:
            geometry = Cylinder(shape.radius, shape.length, origin)
        elif not isinstance(shape, tuple):
            collisions.append(Collision(shape, origin))
    colour, material = None, None
    if lk.visuals and lk.visuals[0].material is not None:
        mat = lk.visuals[0].material
        material = mat.name
        rgba = mat.color if mat.color is not None else colours.get(material)
        if rgba is not None:
            colour = tuple(float(v) for v in rgba.rgba)
    return Link(lk.name, geometry, colour, material, tuple(collisions))  # type: ignore[arg-type]


def _shape(link: str, g: yourdfpy.Geometry | None, el: ET.Element, path: str,
           options: ReadOptions) -> Shape | tuple[()] | None:
    """The shape of a collision element (``()`` for a mesh left out by the options)."""
    capsule = el.find("geometry/capsule")
    if capsule is not None:
        return Capsule(float(capsule.get("radius", "nan")), float(capsule.get("length", "nan")))
    if g is None:
        return None
    if g.cylinder is not None:
        if not (g.cylinder.radius is not None and g.cylinder.length is not None):
            raise FileFormatError(path, f"link {link}: cylinder needs numeric radius and length")
        return CylinderShape(float(g.cylinder.radius), float(g.cylinder.length))
    if g.box is not None:
        return Box(tuple(float(v) for v in g.box.size))  # type: ignore[arg-type]
    if g.sphere is not None:
        return Sphere(float(g.sphere.radius))
    if g.mesh is None:
        return None
    if not options.meshes:
        return ()
    where = Path(path) if Path(path).is_file() else None
    found, tried = options.packages.resolve(g.mesh.filename, where)
    if found is None:
        raise FileFormatError(path, f"link {link}: collision mesh '{g.mesh.filename}' not "
                              "found (looked at " + ", ".join(str(t) for t in tried[:6])
                              + (" ..." if len(tried) > 6 else "") + "; give --package-path "
                              "NAME=DIR)")
    scale = np.broadcast_to(np.asarray(1.0 if g.mesh.scale is None else g.mesh.scale, float),
                            (3,))
    from usar_arm.urdf.meshes import load_mesh  # trimesh: only for a URDF with meshes

    try:
        return load_mesh(found, tuple(scale), options.convex_hull)  # type: ignore[arg-type]
    except ValueError as exc:
        raise FileFormatError(path, f"link {link}: collision mesh {found}: {exc}") from None


def _joint(j: yourdfpy.Joint, origin: ET.Element | None, path: str, notes: list[str]) -> Joint:
    """One joint, its origin from the document's own numbers."""
    jtype = _TYPES.get(j.type)
    if jtype is None:
        if j.type in ("floating", "planar"):
            raise RobotStructureError(f"a {j.type} joint ({j.name}) between {j.parent} and "
                                      f"{j.child}", path, "a fixed base: revolute, continuous, "
                                      "prismatic and fixed joints only")
        raise FileFormatError(path, f"joint {j.name}: type '{j.type}' is not supported "
                              "(revolute, continuous, prismatic, fixed)")
    axis = np.asarray(j.axis if j.axis is not None else (1.0, 0.0, 0.0), float)
    limits = None
    if jtype is not JointType.FIXED:
        lim = j.limit
        if j.type == "continuous":
            lower, upper = -math.pi, math.pi
            notes.append(f"joint {j.name}: continuous, read as [-pi, pi]")
        elif lim is None:
            raise FileFormatError(path, f"joint {j.name}: a {j.type} joint needs <limit>")
        else:
            lower, upper = float(lim.lower or 0.0), float(lim.upper or 0.0)
        limits = JointLimits(lower, upper,
                             float(lim.velocity or 0.0) if lim is not None else 1.0,
                             float(lim.effort or 0.0) if lim is not None else 0.0)
    return Joint(j.name, jtype, j.parent, j.child, _origin(origin, f"joint {j.name}", path),
                 tuple(float(a) for a in axis / np.linalg.norm(axis)),  # type: ignore[arg-type]
                 limits)


def _order(joints: list[Joint], links: list[Link]) -> list[Joint]:
    """Joints from the root outwards (breadth first)."""
    children = {j.child for j in joints}
    frontier = [lk.name for lk in links if lk.name not in children]
    order: list[Joint] = []
    while frontier:
        nxt = []
        for name in frontier:
            for j in joints:
                if j.parent == name:
                    order.append(j)
                    nxt.append(j.child)
        frontier = nxt
    return order


def actuated_joint_names(text: str) -> list[str]:
    """The actuated joints yourdfpy reads in URDF text (an independent check of a written
    description; ValueError when it cannot load it)."""
    try:
        robot = _yourdfpy().URDF.load(
            io.BytesIO(text.encode()), build_scene_graph=False, load_meshes=False)
    except Exception as exc:  # yourdfpy raises many types; all mean "cannot load"
        raise ValueError(str(exc)) from None
    return list(robot.actuated_joint_names)


def viewer_urdf(text: str) -> yourdfpy.URDF:
    """A yourdfpy URDF with its scene graph (no meshes), for the 3D viewer (ValueError when it
    cannot load it)."""
    try:
        return _yourdfpy().URDF.load(
            io.BytesIO(text.encode()), build_scene_graph=True,
                                  load_meshes=False, build_collision_scene_graph=False,
                                  load_collision_meshes=False)
    except Exception as exc:  # yourdfpy raises assorted errors for malformed XML
        raise ValueError(str(exc)) from None
