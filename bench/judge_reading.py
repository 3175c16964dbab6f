"""What the judge reads, read by the judge itself: the URDF's link cylinders and joint limits,
the SRDF's disabled pairs, and the obstacles of a scene: from the scene's YAML file (the
``scene_files`` of a problem file: the shipped ``robots/scenes/*.yaml`` and the generated
``boxes_N.yaml``), parsed here with PyYAML, not from the JSON the solvers read (which
``bench/scenes.py`` writes with usar-arm's own scene parser: a bug there must not reach the
judge).

Nothing here (nor in ``verify.py``) imports ``usar_arm``: the checks that every solver's answers
go through must not share the code that produced ours. XML by ``xml.etree``, YAML by PyYAML,
poses by this module's own roll-pitch-yaw and quaternion formulas, meshes by trimesh, forward
kinematics by Pinocchio from the URDF text. Metres and radians.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

Array = np.ndarray


def rpy_matrix(roll: float, pitch: float, yaw: float) -> Array:
    """URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def quat_matrix(w: float, x: float, y: float, z: float) -> Array:
    """The rotation of a unit quaternion (w, x, y, z); normalised first."""
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def pose(rot: Array, xyz: Any) -> Array:
    """4x4 from a rotation and a translation."""
    out = np.eye(4)
    out[:3, :3] = rot
    out[:3, 3] = [float(v) for v in xyz]
    return out


def _floats(text: str | None, default: str) -> list[float]:
    return [float(v) for v in (text if text is not None else default).split()]


@dataclass(frozen=True)
class LinkCylinder:
    """A link's collision cylinder: its pose in the link frame, radius and length (m)."""

    link: str
    origin: Array
    radius: float
    length: float


@dataclass
class JudgedRobot:
    """The robot as the judge sees it.

    Attributes:
        urdf: the URDF text (Pinocchio builds its model from it).
        cylinders: every link's collision cylinder (links without one are not checked).
        joints: actuated joint names in the URDF's order; lower, upper: their limits.
        disabled: the SRDF's disabled pairs (sorted link-name tuples).
    """

    urdf: str
    cylinders: list[LinkCylinder]
    joints: list[str]
    lower: Array
    upper: Array
    disabled: set[tuple[str, str]] = field(default_factory=set)

    @classmethod
    def from_files(cls, urdf_path: str | Path, srdf_path: str | Path | None) -> JudgedRobot:
        """Read a URDF (and its SRDF, when given)."""
        urdf = Path(urdf_path).read_text(encoding="utf-8")
        srdf = Path(srdf_path).read_text(encoding="utf-8") if srdf_path else None
        return cls.from_text(urdf, srdf)

    @classmethod
    def from_text(cls, urdf: str, srdf: str | None) -> JudgedRobot:
        root = ET.fromstring(urdf)
        cylinders = []
        for link in root.findall("link"):
            for col in link.findall("collision"):
                cyl = col.find("geometry/cylinder")
                if cyl is None:
                    continue
                org = col.find("origin")
                xyz = _floats(org.get("xyz") if org is not None else None, "0 0 0")
                rpy = _floats(org.get("rpy") if org is not None else None, "0 0 0")
                cylinders.append(LinkCylinder(link.get("name", ""), pose(rpy_matrix(*rpy), xyz),
                                              float(cyl.get("radius", "0")),
                                              float(cyl.get("length", "0"))))
        joints, lower, upper = [], [], []
        for joint in root.findall("joint"):
            kind = joint.get("type")
            if kind not in ("revolute", "prismatic", "continuous"):
                continue
            limit = joint.find("limit")
            lo = float(limit.get("lower", "-inf")) if limit is not None else -math.inf
            hi = float(limit.get("upper", "inf")) if limit is not None else math.inf
            if kind == "continuous":
                lo, hi = -math.inf, math.inf
            joints.append(joint.get("name", ""))
            lower.append(lo)
            upper.append(hi)
        disabled: set[tuple[str, str]] = set()
        if srdf:
            for d in ET.fromstring(srdf).findall("disable_collisions"):
                a, b = d.get("link1", ""), d.get("link2", "")
                disabled.add((min(a, b), max(a, b)))
        return cls(urdf, cylinders, joints, np.array(lower), np.array(upper), disabled)


@dataclass(frozen=True)
class Obstacle:
    """One obstacle: ``kind`` (box, cylinder, sphere, mesh), its pose (4x4 in base_link), its
    parameters (box ``size``: full edges; ``radius``, ``length``; mesh ``vertices``, ``faces``)
    and the links allowed to touch it."""

    name: str
    kind: str
    pose: Array
    params: dict[str, Any]
    allow: frozenset[str]

    def bounding_radius(self) -> float:
        """Radius (m) of a sphere about the pose's origin that contains the obstacle."""
        p = self.params
        if self.kind == "box":
            return float(np.linalg.norm(np.asarray(p["size"], float)) / 2)
        if self.kind == "cylinder":
            return math.hypot(p["radius"], p["length"] / 2)
        if self.kind == "sphere":
            return float(p["radius"])
        return float(np.max(np.linalg.norm(p["vertices"], axis=1))) if len(p["vertices"]) else 0.0


def read_scene(items: list[dict[str, Any]]) -> list[Obstacle]:
    """The obstacles of a problem file's scene (``bench/scenes.py`` writes that format)."""
    out = []
    for d in items:
        q = d.get("quat_wxyz", [1.0, 0.0, 0.0, 0.0])
        where = pose(quat_matrix(*(float(v) for v in q)), d["xyz"])
        kind = d["type"]
        if kind == "box":
            params: dict[str, Any] = {"size": [float(v) for v in d["size"]]}
        elif kind == "cylinder":
            params = {"radius": float(d["radius"]), "length": float(d["length"])}
        elif kind == "sphere":
            params = {"radius": float(d["radius"])}
        elif kind == "mesh":
            import trimesh

            mesh = trimesh.load(d["file"], force="mesh")
            params = {"vertices": np.asarray(mesh.vertices, float) * float(d.get("scale", 1.0)),
                      "faces": np.asarray(mesh.faces, np.int32)}
        else:
            raise ValueError(f"the judge does not know obstacle type {kind!r} ({d.get('name')})")
        out.append(Obstacle(str(d.get("name", "")), kind, where, params,
                            frozenset(d.get("allow", []))))
    return out


@dataclass(frozen=True)
class Carried:
    """An object the arm carries, as the judge reads it: its shape (an :class:`Obstacle` whose
    pose is the object's in the frame of ``link``, the grasp), the link it is fixed to and the
    links it may touch (never checked against it, nor is ``link``)."""

    body: Obstacle
    link: str
    touch_links: frozenset[str]

    @property
    def name(self) -> str:
        """The object's name (a scene obstacle of that name is this object: not checked)."""
        return self.body.name


def read_attached(items: list[dict[str, Any]]) -> list[Carried]:
    """The carried objects of a problem file's ``attached`` list: each a scene item (type,
    size/radius/length or mesh file, ``xyz`` and ``quat_wxyz`` in the link's frame) with its
    ``link`` and ``touch_links``."""
    out = []
    for d in items:
        if not isinstance(d.get("link"), str):
            raise ValueError(f"the judge expected the link an attached object is fixed to, got "
                             f"{d!r}")
        (body,) = read_scene([{k: v for k, v in d.items() if k not in ("link", "touch_links")}])
        out.append(Carried(body, d["link"], frozenset(d.get("touch_links", []))))
    return out


def _number_list(value: Any, count: int, what: str) -> list[float]:
    if not isinstance(value, list) or len(value) != count:
        raise ValueError(f"the judge expected {count} numbers for {what}, got {value!r}")
    out = [float(v) for v in value]
    if not all(math.isfinite(v) for v in out):
        raise ValueError(f"the judge expected finite numbers for {what}, got {value!r}")
    return out


def _yaml_shape(obj: dict[str, Any], base: Path, what: str) -> tuple[str, dict[str, Any]]:
    """(kind, params) of one scene-file object: ``box: [x, y, z]``, ``cylinder: {radius,
    length}``, ``sphere: {radius}`` or ``mesh: {file, scale}`` (file relative to the scene)."""
    kinds = [k for k in ("box", "cylinder", "sphere", "mesh") if k in obj]
    if len(kinds) != 1:
        raise ValueError(f"the judge expected one shape for {what}, found {kinds}")
    kind, spec = kinds[0], obj[kinds[0]]
    if kind == "box":
        return kind, {"size": _number_list(spec, 3, f"{what}.box")}
    if kind == "cylinder":
        return kind, {"radius": float(spec["radius"]), "length": float(spec["length"])}
    if kind == "sphere":
        return kind, {"radius": float(spec["radius"])}
    import trimesh

    file = Path(spec["file"])
    mesh = trimesh.load(str(file if file.is_absolute() else base / file), force="mesh")
    return kind, {"vertices": np.asarray(mesh.vertices, float) * float(spec.get("scale", 1.0)),
                  "faces": np.asarray(mesh.faces, np.int32)}


def read_scene_file(path: str | Path) -> list[Obstacle]:
    """The obstacles of a scene YAML file (``name``, ``objects``: each with a ``name``, one
    shape, ``xyz``, optional ``rpy`` (URDF's fixed axes) and ``allow``, or a WorldController
    ``class`` and ``scale`` instead of a shape), read by the judge."""
    import yaml

    path = Path(path)
    doc = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    out = []
    for k, obj in enumerate(doc.get("objects") or []):
        what = f"{path.name} objects[{k}]"
        rpy = _number_list(obj.get("rpy", [0.0, 0.0, 0.0]), 3, f"{what}.rpy")
        where = pose(rpy_matrix(*rpy), _number_list(obj["xyz"], 3, f"{what}.xyz"))
        allow = frozenset(str(a) for a in obj.get("allow") or [])
        if "class" in obj:
            out += _class_boxes(obj, where, allow, what)
            continue
        kind, params = _yaml_shape(obj, path.parent, what)
        out.append(Obstacle(str(obj["name"]), kind, where, params, allow))
    return out


# The WorldController classes a cell spawns, as the judge knows them (read here from the
# simulator's documented class table, docs/simulator.md, not from usar-arm's code): outer edges
# (m) at scale 1 and, for an open container, its wall and floor thickness (m).
_WC_SIZES: dict[str, tuple[tuple[float, float, float], float]] = {
    "wccrate": ((0.30, 0.30, 0.25), 0.0), "wccratered": ((0.30, 0.30, 0.25), 0.0),
    "wccrategreen": ((0.30, 0.30, 0.25), 0.0), "wccrateblue": ((0.30, 0.30, 0.25), 0.0),
    "wckivapallet": ((0.30, 0.30, 0.25), 0.0), "wcpallet": ((1.20, 0.80, 0.144), 0.0),
    "wcobjectbin": ((0.40, 0.30, 0.20), 0.015), "wckittray": ((0.50, 0.35, 0.05), 0.01),
    "wckittraysmall": ((0.30, 0.20, 0.04), 0.01)}


def _class_boxes(obj: dict[str, Any], where: Array, allow: frozenset[str],
                 what: str) -> list[Obstacle]:
    """A WorldController object of a scene file (``class``, ``scale``; its origin the centre
    of its outline): one box, or an open container's floor and four walls named
    ``<name>/floor``, ``<name>/wall_front`` (+x), ``wall_back``, ``wall_left`` (+y),
    ``wall_right``, as the judge builds them."""
    key = str(obj["class"]).rpartition(".")[2].lower()
    if key not in _WC_SIZES:
        raise ValueError(f"the judge does not know WorldController class {obj['class']!r} "
                         f"({what})")
    size, wall = _WC_SIZES[key]
    scale = _number_list(obj.get("scale", [1.0, 1.0, 1.0]), 3, f"{what}.scale")
    x, y, z = (size[i] * scale[i] for i in range(3))
    name = str(obj["name"])
    if wall == 0.0:
        return [Obstacle(name, "box", where, {"size": [x, y, z]}, allow)]
    t = [wall * s for s in scale]
    h = z - t[2]  # the walls stand on the floor
    pieces = {"floor": ((0.0, 0.0, (t[2] - z) / 2), (x, y, t[2])),
              "wall_front": (((x - t[0]) / 2, 0.0, t[2] / 2), (t[0], y, h)),
              "wall_back": (((t[0] - x) / 2, 0.0, t[2] / 2), (t[0], y, h)),
              "wall_left": ((0.0, (y - t[1]) / 2, t[2] / 2), (x - 2 * t[0], t[1], h)),
              "wall_right": ((0.0, (t[1] - y) / 2, t[2] / 2), (x - 2 * t[0], t[1], h))}
    return [Obstacle(f"{name}/{piece}", "box", where @ pose(np.eye(3), centre),
                     {"size": list(edges)}, allow)
            for piece, (centre, edges) in pieces.items()]


def scene_obstacles(spec: dict[str, Any], scene: str) -> list[Obstacle]:
    """The obstacles of a problem file's scene as the judge reads them: from the scene's YAML
    file (``spec["scene_files"]``); a problem file without one (hand-made test files, scenes
    that exist only as obstacle lists) falls back to the obstacle list itself."""
    files = spec.get("scene_files") or {}
    if scene in files:
        return read_scene_file(files[scene])
    return read_scene(spec["scenes"][scene])
