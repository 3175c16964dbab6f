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
      - {name: part, class: WCCrate, xyz: [1.45, -0.45, 0.75], scale: [0.4, 0.4, 0.4]}

An object may name a WorldController class instead of a shape (a work cell's description,
:mod:`usar_arm.core.cell`: the shipped ``table`` is the demo's cell, whose static objects are
also the embedded simulator's default scenery): each becomes its class's shapes (an open
container, a floor and four walls, as ``<name>/floor``, ``<name>/wall_front``...).

Every error names the file, the line and the field, and says what was expected. Keys are checked
at every level (a misspelt ``objetcs:`` or ``raduis:`` is an error, never silently ignored), and
every number must be finite. The file is read by :mod:`usar_arm.core.cell`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from usar_arm.core.cell import SHAPES, find_description, parse_cell, read_yaml_file
from usar_arm.core.errors import FileFormatError
from usar_arm.planning.cell_scene import cell_objects
from usar_arm.planning.scene import Scene

__all__ = ["BUILTIN", "SHAPES", "load_scene", "parse_scene", "validate_allow"]

BUILTIN = ("empty", "table", "shelf", "cage")


def parse_scene(data: Any, path: str, base: Path) -> Scene:
    """A Scene from parsed YAML (as :func:`usar_arm.core.yamlio.load_yaml` returns it): its
    static objects, then the objects it spawns (``base``: the folder of relative mesh files)."""
    cell = parse_cell(data, path, base)
    return Scene(cell.name, cell_objects(cell, path))


def load_scene(path_or_name: str | Path) -> Scene:
    """A scene from a YAML file, or one of the shipped scenes by name (empty, table, shelf,
    cage)."""
    path, name = find_description(path_or_name, BUILTIN, "scene")
    return parse_scene(read_yaml_file(path, name), name, path.parent)


def validate_allow(scene: Scene, links: set[str], path: str = "") -> None:
    """Every ``allow`` entry must name a robot link."""
    for obj in scene.objects:
        for link in obj.allow:
            if link not in links:
                raise FileFormatError(path or scene.name,
                                      f"object '{obj.name}' allows unknown link '{link}' "
                                      f"(links: {', '.join(sorted(links))})",
                                      field=f"{obj.name}.allow")
