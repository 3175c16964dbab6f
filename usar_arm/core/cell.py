"""A work cell's one description (YAML): its static scenery and the objects a WorldController
spawns in it, read by both the simulator and the planner.

Format (lengths in m, angles in rad; REP-103, z up, in the frame of a robot standing at
``RobotStart1``, the world origin)::

    name: table
    description: a work table in front of the arm
    objects:                      # the static scenery (a shape) and the spawned objects (a class)
      - name: top
        box: [1.0, 1.6, 0.05]                 # edge lengths x, y, z
        xyz: [1.55, 0.0, 0.675]               # centre
        rpy: [0, 0, 0]                        # optional
      - {name: leg, cylinder: {radius: 0.03, length: 0.65}, xyz: [1.1, -0.75, 0.325]}
      - {name: ball, sphere: {radius: 0.1}, xyz: [1.2, 0.4, 0.8]}
      - {name: fixture, mesh: {file: meshes/fixture.stl, scale: 1.0}, xyz: [1.6, 0.3, 0.7]}
      - {name: floor, box: [6, 6, 0.05], xyz: [0, 0, -0.025], allow: [base_link]}
      # A WorldController object (CONTROL {Type Create}): a class instead of a shape.
      - {name: part, class: WCCrate, xyz: [1.45, -0.45, 0.75], scale: [0.4, 0.4, 0.4],
         physics: RigidBody}

Every error names the file, the line and the field, and says what was expected; keys are
checked at every level and every number must be finite. Meshes stay file references here (the
planner loads them with trimesh, the simulator hands them to MuJoCo).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from usar_arm.core.errors import FileFormatError
from usar_arm.core.shapes import Box, CylinderShape, Sphere
from usar_arm.core.spatial import Array, transform_from_xyz_rpy
from usar_arm.core.wc_classes import WC_CLASSES, WcClass, find_class
from usar_arm.core.yamlio import line_of, load_yaml

SHIPPED_FOLDER = ("data", "scenes")
"""Where the shipped descriptions live, below the ``usar_arm`` package."""
SHAPES = ("box", "cylinder", "sphere", "mesh")
KEYS = {"name", "xyz", "rpy", "allow", *SHAPES}
SPAWN_KEYS = {"name", "class", "xyz", "rpy", "scale", "physics", "permanent", "memory",
              "material"}
TOP_KEYS = {"name", "description", "objects"}
SHAPE_KEYS = {"cylinder": ("radius", "length"), "sphere": ("radius",), "mesh": ("file", "scale")}
"""The keys of each shape given as a mapping (a box is a list of edge lengths)."""


@dataclass(frozen=True)
class MeshFile:
    """A mesh by reference: its file (absolute) and uniform scale."""

    path: Path
    scale: float = 1.0
    given: str = ""
    """The file name as the description gives it (for messages)."""
    line: int | None = None
    field: str = ""
    """Where the description names it (for the error of a mesh that does not load)."""


CellShape = Box | CylinderShape | Sphere | MeshFile


@dataclass(frozen=True, eq=False)
class StaticPiece:
    """A piece of static scenery: name, shape, pose (4x4, REP-103 cell frame), and the robot
    links allowed to touch it (a planner's notion; the base standing on the floor)."""

    name: str
    shape: CellShape
    pose: Array
    allow: tuple[str, ...] = ()


@dataclass(frozen=True, eq=False)
class Placement:
    """A WorldController object to spawn: its name, class, pose (4x4, REP-103 cell frame; the
    origin is the centre of its bounding box), scale, and CONTROL Create's other fields."""

    name: str
    wc_class: WcClass
    pose: Array
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    physics: str = "RigidBody"
    permanent: bool = False
    memory: str = ""
    material: str = ""


@dataclass(frozen=True, eq=False)
class Cell:
    """A cell: its static scenery and the objects spawned into it."""

    name: str
    description: str
    static: tuple[StaticPiece, ...]
    spawn: tuple[Placement, ...] = ()
    order: tuple[str, ...] = ()
    """Every object's name in the description's order."""


def _finite(value: Any) -> bool:
    """True for an int or float (not a bool) that is a finite float64."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an int beyond float64
        return False


def _unknown_keys(mapping: dict[Any, Any], known: Any) -> list[Any]:
    """The keys of ``mapping`` not in ``known``, sorted as text (YAML keys may be any type)."""
    return sorted((k for k in mapping if k not in known), key=str)


class CellReader:
    """Field-by-field checks of one description file; every failure names file, line, field."""

    def __init__(self, path: str, base: Path):
        self.path = path
        self.base = base

    def fail(self, problem: str, container: Any, key: Any, field: str) -> FileFormatError:
        """The error for ``container[key]`` at ``field``."""
        return FileFormatError(self.path, problem, line=line_of(container, key), field=field)

    def numbers(self, container: Any, key: Any, field: str, count: int,
                positive: bool = False) -> list[float]:
        """``count`` finite numbers (positive ones with ``positive``)."""
        value = container[key]
        ok = isinstance(value, list) and len(value) == count and all(_finite(v) for v in value)
        if not ok:
            raise self.fail(f"expected {count} finite numbers, got {value!r}", container, key,
                            field)
        if positive and any(v <= 0 for v in value):
            raise self.fail(f"expected positive numbers, got {value!r}", container, key, field)
        return [float(v) for v in value]

    def positive(self, container: Any, key: str, field: str) -> float:
        """A positive finite number."""
        if not isinstance(container, dict) or key not in container:
            raise self.fail(f"missing '{key}'", container, None, field)
        value = container[key]
        if not _finite(value) or not value > 0:
            raise self.fail(f"expected a positive finite number, got {value!r}", container, key,
                            f"{field}.{key}")
        return float(value)

    def keys(self, spec: Any, container: Any, kind: str, field: str) -> None:
        """A shape given as a mapping must use exactly the keys of its kind."""
        known = SHAPE_KEYS[kind]
        example = "{" + ", ".join(f"{k}: .." for k in known) + "}"
        if not isinstance(spec, dict):
            raise self.fail(f"expected a mapping {example}, got {spec!r}", container, kind, field)
        unknown = _unknown_keys(spec, known)
        if unknown:
            raise self.fail(f"unknown key '{unknown[0]}' (expected: {', '.join(known)})", spec,
                            unknown[0], f"{field}.{unknown[0]}")

    def shape(self, obj: dict[str, Any], kind: str, field: str) -> CellShape:
        """The one shape of an object."""
        spec = obj[kind]
        where = f"{field}.{kind}"
        if kind == "box":
            return Box(tuple(self.numbers(obj, kind, where, 3, positive=True)))  # type: ignore[arg-type]
        self.keys(spec, obj, kind, where)
        if kind == "sphere":
            return Sphere(self.positive(spec, "radius", where))
        if kind == "cylinder":
            return CylinderShape(self.positive(spec, "radius", where),
                                 self.positive(spec, "length", where))
        if not isinstance(spec.get("file"), str) or not spec["file"]:
            raise self.fail(f"expected the mesh file name (STL/OBJ, relative to the file), got "
                            f"{spec.get('file')!r}", spec, "file" if "file" in spec else None,
                            f"{where}.file")
        scale = self.positive(spec, "scale", where) if "scale" in spec else 1.0
        file = Path(spec["file"])
        return MeshFile(file if file.is_absolute() else self.base / file, scale, spec["file"],
                        line_of(spec, "file"), f"{where}.file")

    def pose(self, obj: dict[str, Any], label: str, field: str) -> Array:
        """An object's ``xyz`` (required) and ``rpy`` (optional) as a 4x4 pose."""
        if "xyz" not in obj:
            raise self.fail(f"object '{label}' needs 'xyz' (its centre, m)", obj, None,
                            f"{field}.xyz")
        xyz = self.numbers(obj, "xyz", f"{field}.xyz", 3)
        rpy = self.numbers(obj, "rpy", f"{field}.rpy", 3) if "rpy" in obj else [0.0, 0.0, 0.0]
        return transform_from_xyz_rpy(xyz, rpy)

    def entries(self, data: dict[str, Any], key: str, known: set[str]
                ) -> list[tuple[str, str, dict[str, Any]]]:
        """(name, field, mapping) of each entry of the list ``data[key]``, names unique."""
        raw = data.get(key) or []
        if not isinstance(raw, list):
            raise self.fail(f"'{key}' must be a list", data, key, key)
        out: list[tuple[str, str, dict[str, Any]]] = []
        seen: dict[str, int] = {}
        for i, obj in enumerate(raw):
            field = f"{key}[{i}]"
            if not isinstance(obj, dict):
                raise self.fail("expected a mapping (name, ...)", raw, i, field)
            unknown = _unknown_keys(obj, known)
            if unknown:
                raise self.fail(f"unknown key '{unknown[0]}' (expected: "
                                f"{', '.join(sorted(known))})", obj, unknown[0],
                                f"{field}.{unknown[0]}")
            label = obj.get("name")
            if not isinstance(label, str) or not label:
                raise self.fail("every object needs a 'name'", obj,
                                "name" if "name" in obj else None, f"{field}.name")
            if label in seen:
                raise self.fail(f"duplicate object name '{label}' (first at line "
                                f"{seen[label]})", obj, "name", f"{field}.name")
            seen[label] = line_of(obj, "name") or 0
            out.append((label, field, obj))
        return out

    def objects(self, data: dict[str, Any]
                ) -> tuple[tuple[StaticPiece, ...], tuple[Placement, ...], tuple[str, ...]]:
        """The ``objects`` list: the static pieces (with a shape), the WorldController's
        objects (with a ``class``), and every name in the file's order."""
        static, spawn = [], []
        entries = self.entries(data, "objects", KEYS | SPAWN_KEYS)
        for label, field, obj in entries:
            known = SPAWN_KEYS if "class" in obj else KEYS
            wrong = _unknown_keys(obj, known)
            if wrong:
                kind = "a WorldController object" if "class" in obj else "a static object"
                raise self.fail(f"'{wrong[0]}' is not a key of {kind} (expected: "
                                f"{', '.join(sorted(known))})", obj, wrong[0],
                                f"{field}.{wrong[0]}")
            if "class" in obj:
                spawn.append(self.spawned(label, field, obj))
            else:
                static.append(self.piece(label, field, obj))
        return tuple(static), tuple(spawn), tuple(label for label, _, _ in entries)

    def piece(self, label: str, field: str, obj: dict[str, Any]) -> StaticPiece:
        """A static object."""
        kinds = [k for k in SHAPES if k in obj]
        if len(kinds) != 1:
            raise self.fail(f"object '{label}' needs exactly one shape of: "
                            f"{', '.join(SHAPES)} (found {kinds or 'none'})", obj, None,
                            field)
        shape = self.shape(obj, kinds[0], field)
        pose = self.pose(obj, label, field)
        allow = obj.get("allow", [])
        if not isinstance(allow, list) or not all(isinstance(a, str) for a in allow):
            raise self.fail("'allow' must be a list of link names", obj, "allow",
                            f"{field}.allow")
        return StaticPiece(label, shape, pose, tuple(allow))

    def spawned(self, label: str, field: str, obj: dict[str, Any]) -> Placement:
        """A WorldController object."""
        name = obj.get("class")
        cls = find_class(name) if isinstance(name, str) else None
        if cls is None:
            raise self.fail(f"'{label}' needs a WorldController class (known: "
                            f"{', '.join(_known())}), got {name!r}", obj,
                            "class" if "class" in obj else None, f"{field}.class")
        scale = (tuple(self.numbers(obj, "scale", f"{field}.scale", 3, positive=True))
                 if "scale" in obj else (1.0, 1.0, 1.0))
        texts = {}
        for key, default in (("physics", "RigidBody"), ("memory", ""), ("material", "")):
            value = obj.get(key, default)
            if not isinstance(value, str):
                raise self.fail(f"expected text, got {value!r}", obj, key, f"{field}.{key}")
            texts[key] = value
        permanent = obj.get("permanent", False)
        if not isinstance(permanent, bool):
            raise self.fail(f"expected true or false, got {permanent!r}", obj, "permanent",
                            f"{field}.permanent")
        return Placement(label, cls, self.pose(obj, label, field), scale,  # type: ignore[arg-type]
                         texts["physics"], permanent, texts["memory"], texts["material"])


def _known() -> list[str]:
    return sorted(WC_CLASSES)


def parse_cell(data: Any, path: str, base: Path) -> Cell:
    """A Cell from parsed YAML (:func:`usar_arm.core.yamlio.load_yaml`'s result); ``base`` is
    the folder mesh files are relative to."""
    reader = CellReader(path, base)
    if not isinstance(data, dict):
        raise FileFormatError(path, "expected a mapping with 'name' and 'objects'",
                              line=line_of(data))
    unknown = _unknown_keys(data, TOP_KEYS)
    if unknown:
        raise reader.fail(f"unknown key '{unknown[0]}' (expected: "
                          f"{', '.join(sorted(TOP_KEYS))})", data, unknown[0], str(unknown[0]))
    name = data.get("name")
    if name is None:
        name = Path(path).stem
    elif not isinstance(name, str):
        raise reader.fail(f"expected the name as text, got {name!r}", data, "name", "name")
    description = data.get("description", "")
    static, spawn, order = reader.objects(data)
    return Cell(name, str(description), static, spawn, order)


def shipped_path(name: str) -> Path | None:
    """The file of the shipped description (scene) called ``name``, or None."""
    entry = resources.files("usar_arm").joinpath(*SHIPPED_FOLDER, f"{name}.yaml")
    return Path(str(entry)) if entry.is_file() else None


def read_yaml_file(path: Path, name: str) -> Any:
    """:func:`~usar_arm.core.yamlio.load_yaml`, with the failures PyYAML raises outside
    ``YAMLError`` turned into FileFormatError as well."""
    try:
        return load_yaml(path)
    except UnicodeDecodeError as exc:
        raise FileFormatError(name, f"not UTF-8 text: byte 0x{exc.object[exc.start]:02x} at "
                              f"offset {exc.start}") from None
    except RecursionError:
        raise FileFormatError(name, "not valid YAML: nested too deeply") from None
    except TypeError as exc:  # a list or mapping used as a mapping key: unhashable
        raise FileFormatError(name, f"not valid YAML: a list or mapping used as a key ({exc})") \
            from None
    except ValueError as exc:  # a tagged or implicit scalar PyYAML cannot convert
        raise FileFormatError(name, f"not valid YAML: {exc}") from None


def find_description(path_or_name: str | Path, shipped: tuple[str, ...], kind: str = "description"
                     ) -> tuple[Path, str]:
    """The file of ``path_or_name``: the file itself, or the shipped one of that name when it
    is in ``shipped`` and no such file exists; with the name errors should give it.

    Raises:
        FileFormatError: neither (the shipped names listed), or an unusable file name.
    """
    text = str(path_or_name)
    path = Path(text)
    try:
        exists = path.exists()
    except OSError as exc:  # e.g. a name longer than the file system allows
        raise FileFormatError(text, f"not a usable file name: {exc.strerror or exc}") from None
    found = shipped_path(text) if text in shipped and not exists else None
    if found is not None:
        return found, str(found)
    if not exists:
        raise FileFormatError(text, f"no such {kind} file (shipped: {', '.join(shipped)})")
    return path, text


def load_cell(path_or_name: str | Path) -> Cell:
    """A cell from a YAML file, or a shipped one by name (``table``).

    Raises:
        FileFormatError: no such file, or an error in it (file, line and field named).
    """
    path, name = find_description(path_or_name, ("table",))
    return parse_cell(read_yaml_file(path, name), name, path.parent)


@dataclass(frozen=True, eq=False)
class Sighting:
    """A WorldController object as the simulator reports it: its name, class, pose (4x4,
    z-down world: GetSTA's Location and Rotation) and world-axis bounding box size (m)."""

    name: str
    wc_class: WcClass
    pose: Array
    size: tuple[float, float, float]
    memory: str = ""
