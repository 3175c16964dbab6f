"""Scene files (YAML): obstacles in base_link, checked field by field.

Format (lengths in m, angles in rad)::

    name: table
    description: a work table in front of the arm
    objects:
      - name: top
        box: [1.0, 1.6, 0.05]            # edge lengths x, y, z
        xyz: [1.55, 0.0, 0.675]          # centre, base_link frame
        rpy: [0, 0, 0]                   # optional
      - name: leg
        cylinder: {radius: 0.03, length: 0.65}   # along the object's z axis
        xyz: [1.1, -0.75, 0.325]
      - name: ball
        sphere: {radius: 0.1}
        xyz: [1.2, 0.4, 0.8]
      - name: fixture
        mesh: {file: meshes/fixture.stl, scale: 1.0}  # STL/OBJ, relative to this file
        xyz: [1.6, 0.3, 0.7]
      - name: floor
        box: [6, 6, 0.05]
        xyz: [0, 0, -0.025]
        allow: [base_link]               # links allowed to touch it

Every error names the file, the line and the field, and says what was expected. Keys are checked
at every level (a misspelt ``objetcs:`` or ``raduis:`` is an error, never silently ignored), and
every number must be finite.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path
from typing import Any

from usar_arm.core.errors import FileFormatError
from usar_arm.core.named_file import resolve_name
from usar_arm.core.spatial import transform_from_xyz_rpy
from usar_arm.core.yamlio import line_of, load_yaml
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, SceneObject, Shape, Sphere

SHAPES = ("box", "cylinder", "sphere", "mesh")
KEYS = {"name", "xyz", "rpy", "allow", *SHAPES}
TOP_KEYS = {"name", "description", "objects"}
SHAPE_KEYS = {"cylinder": ("radius", "length"), "sphere": ("radius",), "mesh": ("file", "scale")}
"""The keys of each shape given as a mapping (a box is a list of edge lengths)."""
BUILTIN = ("empty", "table", "shelf", "cage")


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


class _Ctx:
    def __init__(self, path: str):
        self.path = path

    def fail(self, problem: str, container: Any, key: Any, field: str) -> FileFormatError:
        return FileFormatError(self.path, problem, line=line_of(container, key), field=field)

    def numbers(self, container: Any, key: Any, field: str, count: int,
                positive: bool = False) -> list[float]:
        value = container[key]
        ok = isinstance(value, list) and len(value) == count and all(_finite(v) for v in value)
        if not ok:
            raise self.fail(f"expected {count} finite numbers, got {value!r}", container, key,
                            field)
        if positive and any(v <= 0 for v in value):
            raise self.fail(f"expected positive numbers, got {value!r}", container, key, field)
        return [float(v) for v in value]

    def positive(self, container: Any, key: str, field: str) -> float:
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


def _shape(ctx: _Ctx, obj: dict[str, Any], kind: str, field: str, base: Path) -> Shape:
    spec = obj[kind]
    where = f"{field}.{kind}"
    if kind == "box":
        return Box(tuple(ctx.numbers(obj, kind, where, 3, positive=True)))  # type: ignore[arg-type]
    ctx.keys(spec, obj, kind, where)
    if kind == "sphere":
        return Sphere(ctx.positive(spec, "radius", where))
    if kind == "cylinder":
        return CylinderShape(ctx.positive(spec, "radius", where),
                             ctx.positive(spec, "length", where))
    if not isinstance(spec.get("file"), str) or not spec["file"]:
        raise ctx.fail(f"expected the mesh file name (STL/OBJ, relative to the scene file), got "
                       f"{spec.get('file')!r}", spec, "file" if "file" in spec else None,
                       f"{where}.file")
    scale = ctx.positive(spec, "scale", where) if "scale" in spec else 1.0
    file = Path(spec["file"])
    full = file if file.is_absolute() else base / file
    from usar_arm.urdf.meshes import load_mesh  # trimesh: only when a scene has a mesh

    try:
        mesh = load_mesh(full, (scale, scale, scale))
    except ValueError as exc:
        raise ctx.fail(f"cannot load mesh {full}: {exc}", spec, "file", f"{where}.file") from None
    return Mesh(mesh.vertices, mesh.faces, str(file))


def parse_scene(data: Any, path: str, base: Path) -> Scene:
    """A Scene from parsed YAML (as :func:`usar_arm.core.yamlio.load_yaml` returns it)."""
    ctx = _Ctx(path)
    if not isinstance(data, dict):
        raise FileFormatError(path, "expected a mapping with 'name' and 'objects'",
                              line=line_of(data))
    unknown_top = _unknown_keys(data, TOP_KEYS)
    if unknown_top:
        raise ctx.fail(f"unknown key '{unknown_top[0]}' (expected: "
                       f"{', '.join(sorted(TOP_KEYS))})", data, unknown_top[0],
                       str(unknown_top[0]))
    name = data.get("name")
    if name is None:
        name = Path(path).stem
    elif not isinstance(name, str):
        raise ctx.fail(f"expected the scene's name as text, got {name!r}", data, "name", "name")
    objects_raw = data.get("objects", [])
    if objects_raw is None:
        objects_raw = []
    if not isinstance(objects_raw, list):
        raise ctx.fail("'objects' must be a list", data, "objects", "objects")
    objects: list[SceneObject] = []
    seen: dict[str, int] = {}
    for i, obj in enumerate(objects_raw):
        field = f"objects[{i}]"
        if not isinstance(obj, dict):
            raise ctx.fail("expected a mapping (name, one shape, xyz, ...)", objects_raw, i, field)
        unknown = _unknown_keys(obj, KEYS)
        if unknown:
            raise ctx.fail(f"unknown key '{unknown[0]}' (expected: {', '.join(sorted(KEYS))})",
                           obj, unknown[0], f"{field}.{unknown[0]}")
        label = obj.get("name")
        if not isinstance(label, str) or not label:
            raise ctx.fail("every object needs a 'name'", obj, "name" if "name" in obj else None,
                           f"{field}.name")
        if label in seen:
            raise ctx.fail(f"duplicate object name '{label}' (first at line {seen[label]})", obj,
                           "name", f"{field}.name")
        seen[label] = line_of(obj, "name") or 0
        kinds = [k for k in SHAPES if k in obj]
        if len(kinds) != 1:
            raise ctx.fail(f"object '{label}' needs exactly one shape of: {', '.join(SHAPES)} "
                           f"(found {kinds or 'none'})", obj, None, field)
        shape = _shape(ctx, obj, kinds[0], field, base)
        if "xyz" not in obj:
            raise ctx.fail(f"object '{label}' needs 'xyz' (its centre in base_link, m)", obj,
                           None, f"{field}.xyz")
        xyz = ctx.numbers(obj, "xyz", f"{field}.xyz", 3)
        rpy = ctx.numbers(obj, "rpy", f"{field}.rpy", 3) if "rpy" in obj else [0.0, 0.0, 0.0]
        allow = obj.get("allow", [])
        if not isinstance(allow, list) or not all(isinstance(a, str) for a in allow):
            raise ctx.fail("'allow' must be a list of link names", obj, "allow",
                           f"{field}.allow")
        objects.append(SceneObject(label, shape, transform_from_xyz_rpy(xyz, rpy), tuple(allow)))
    return Scene(name, tuple(objects))


def load_scene(path_or_name: str | Path) -> Scene:
    """A scene from a YAML file, or one of the shipped scenes by name (empty, table, shelf,
    cage; a name or a path by :mod:`usar_arm.core.named_file`'s rule).

    Raises:
        FileFormatError: no such scene (what was tried), or the file is not a scene.
    """
    named = resolve_name(path_or_name, "scene", BUILTIN)
    if named.shipped is not None:
        with resources.as_file(resources.files("usar_arm") / "data" / "scenes"
                               / f"{named.shipped}.yaml") as fp:
            return load_scene(fp)
    assert named.path is not None
    return parse_scene(_read_yaml(named.path, named.given), named.given, named.path.parent)


def _read_yaml(path: Path, name: str) -> Any:
    """:func:`load_yaml`, with the failures PyYAML raises outside ``YAMLError`` (and that
    ``load_yaml`` lets through) turned into FileFormatError as well."""
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


def validate_allow(scene: Scene, links: set[str], path: str = "") -> None:
    """Every ``allow`` entry must name a robot link."""
    for obj in scene.objects:
        for link in obj.allow:
            if link not in links:
                raise FileFormatError(path or scene.name,
                                      f"object '{obj.name}' allows unknown link '{link}' "
                                      f"(links: {', '.join(sorted(links))})",
                                      field=f"{obj.name}.allow")
