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

Every error names the file, the line and the field, and says what was expected.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.errors import FileFormatError
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, SceneObject, Shape, Sphere
from usar_arm.spatial import transform_from_xyz_rpy
from usar_arm.yamlio import line_of, load_yaml

SHAPES = ("box", "cylinder", "sphere", "mesh")
KEYS = {"name", "xyz", "rpy", "allow", *SHAPES}
BUILTIN = ("empty", "table", "shelf", "cage")


class _Ctx:
    def __init__(self, path: str):
        self.path = path

    def fail(self, problem: str, container: Any, key: Any, field: str) -> FileFormatError:
        return FileFormatError(self.path, problem, line=line_of(container, key), field=field)

    def numbers(self, container: Any, key: Any, field: str, count: int,
                positive: bool = False) -> list[float]:
        value = container[key]
        ok = isinstance(value, list) and len(value) == count and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in value)
        if not ok:
            raise self.fail(f"expected {count} numbers, got {value!r}", container, key, field)
        if positive and any(v <= 0 for v in value):
            raise self.fail(f"expected positive numbers, got {value!r}", container, key, field)
        return [float(v) for v in value]

    def positive(self, container: Any, key: str, field: str) -> float:
        if not isinstance(container, dict) or key not in container:
            raise self.fail(f"missing '{key}'", container, None, field)
        value = container[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise self.fail(f"expected a positive number, got {value!r}", container, key,
                            f"{field}.{key}")
        return float(value)


def _shape(ctx: _Ctx, obj: dict[str, Any], kind: str, field: str, base: Path) -> Shape:
    spec = obj[kind]
    where = f"{field}.{kind}"
    if kind == "box":
        return Box(tuple(ctx.numbers(obj, kind, where, 3, positive=True)))  # type: ignore[arg-type]
    if kind == "sphere":
        return Sphere(ctx.positive(spec, "radius", where))
    if kind == "cylinder":
        return CylinderShape(ctx.positive(spec, "radius", where),
                             ctx.positive(spec, "length", where))
    if not isinstance(spec, dict) or "file" not in spec:
        raise ctx.fail("expected {file: PATH, scale: S}", obj, kind, where)
    scale = ctx.positive(spec, "scale", where) if "scale" in spec else 1.0
    file = Path(str(spec["file"]))
    full = file if file.is_absolute() else base / file
    try:
        import trimesh

        mesh = trimesh.load(str(full), force="mesh")
    except Exception as exc:  # trimesh raises many types for bad files
        raise ctx.fail(f"cannot load mesh {full}: {exc}", spec, "file", f"{where}.file") from None
    if len(mesh.faces) == 0:
        raise ctx.fail(f"mesh {full} has no triangles", spec, "file", f"{where}.file")
    return Mesh(np.asarray(mesh.vertices, float) * scale, np.asarray(mesh.faces, np.int64),
                str(file))


def parse_scene(data: Any, path: str, base: Path) -> Scene:
    """A Scene from parsed YAML (as :func:`usar_arm.yamlio.load_yaml` returns it)."""
    ctx = _Ctx(path)
    if not isinstance(data, dict):
        raise FileFormatError(path, "expected a mapping with 'name' and 'objects'",
                              line=line_of(data))
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
        unknown = sorted(set(obj) - KEYS)
        if unknown:
            raise ctx.fail(f"unknown key '{unknown[0]}' (expected: {', '.join(sorted(KEYS))})",
                           obj, unknown[0], f"{field}.{unknown[0]}")
        name = obj.get("name")
        if not isinstance(name, str) or not name:
            raise ctx.fail("every object needs a 'name'", obj, "name" if "name" in obj else None,
                           f"{field}.name")
        if name in seen:
            raise ctx.fail(f"duplicate object name '{name}' (first at line {seen[name]})", obj,
                           "name", f"{field}.name")
        seen[name] = line_of(obj, "name") or 0
        kinds = [k for k in SHAPES if k in obj]
        if len(kinds) != 1:
            raise ctx.fail(f"object '{name}' needs exactly one shape of: {', '.join(SHAPES)} "
                           f"(found {kinds or 'none'})", obj, None, field)
        shape = _shape(ctx, obj, kinds[0], field, base)
        if "xyz" not in obj:
            raise ctx.fail(f"object '{name}' needs 'xyz' (its centre in base_link, m)", obj,
                           None, f"{field}.xyz")
        xyz = ctx.numbers(obj, "xyz", f"{field}.xyz", 3)
        rpy = ctx.numbers(obj, "rpy", f"{field}.rpy", 3) if "rpy" in obj else [0.0, 0.0, 0.0]
        allow = obj.get("allow", [])
        if not isinstance(allow, list) or not all(isinstance(a, str) for a in allow):
            raise ctx.fail("'allow' must be a list of link names", obj, "allow",
                           f"{field}.allow")
        objects.append(SceneObject(name, shape, transform_from_xyz_rpy(xyz, rpy), tuple(allow)))
    name = data.get("name", Path(path).stem)
    return Scene(str(name), tuple(objects))


def load_scene(path_or_name: str | Path) -> Scene:
    """A scene from a YAML file, or one of the shipped scenes by name (empty, table, shelf,
    cage)."""
    text = str(path_or_name)
    if text in BUILTIN and not Path(text).exists():
        with resources.as_file(resources.files("usar_arm") / "data" / "scenes"
                               / f"{text}.yaml") as fp:
            return load_scene(fp)
    path = Path(text)
    if not path.exists():
        raise FileFormatError(text, f"no such scene file (shipped scenes: {', '.join(BUILTIN)})")
    return parse_scene(load_yaml(path), text, path.parent)


def validate_allow(scene: Scene, links: set[str], path: str = "") -> None:
    """Every ``allow`` entry must name a robot link."""
    for obj in scene.objects:
        for link in obj.allow:
            if link not in links:
                raise FileFormatError(path or scene.name,
                                      f"object '{obj.name}' allows unknown link '{link}' "
                                      f"(links: {', '.join(sorted(links))})",
                                      field=f"{obj.name}.allow")
