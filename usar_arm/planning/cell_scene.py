"""A work cell as a planning Scene: its static scenery, and the WorldController's objects from
the description or from what the simulator says is really there (its GetSTA reply, with each
object's class from the per-class queries: :meth:`usar_arm.usarsim.world_controller.
WorldControllerClient.sightings`), so that the arm plans around what is really there.

An object of a WorldController class becomes its class's boxes (:mod:`usar_arm.core.wc_classes`):
one box named after the object for a solid one, and for an open container its floor and four
walls, named ``<object>/floor``, ``<object>/wall_front``... so a part can be planned *into* it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from usar_arm.core.cell import Cell, CellShape, MeshFile, Sighting
from usar_arm.core.errors import FileFormatError
from usar_arm.core.spatial import FLIP_X, Array, invert, transform
from usar_arm.core.wc_classes import WcClass
from usar_arm.planning.scene import Box, Mesh, Scene, SceneObject, Shape

_FLIP = transform(FLIP_X)
"""USARSim (z down) <-> REP-103 (z up): the same 4x4 both ways."""


def solid(shape: CellShape, path: str) -> Shape:
    """A cell file's shape as the planner's: a mesh file loaded (trimesh, only then), the
    others as they are.

    Raises:
        FileFormatError: the mesh cannot be loaded, at the line and field of ``path`` (the file
            the shape was read from) that named it.
    """
    if not isinstance(shape, MeshFile):
        return shape
    from usar_arm.urdf.meshes import load_mesh  # trimesh: only when a file has a mesh

    try:
        mesh = load_mesh(shape.path, (shape.scale, shape.scale, shape.scale))
    except ValueError as exc:
        raise FileFormatError(path, f"cannot load mesh {shape.path}: {exc}", line=shape.line,
                              field=shape.field) from None
    return Mesh(mesh.vertices, mesh.faces, shape.given or str(shape.path))


def wc_object_pieces(name: str, wc_class: WcClass, pose: Array,
                     scale: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> list[SceneObject]:
    """The obstacles of a WorldController object at ``pose`` (4x4, base_link; its origin is
    its bounding box's centre) and ``scale``: one box, or a container's floor and walls."""
    boxes = wc_class.boxes(scale)
    if len(boxes) == 1:
        return [SceneObject(name, Box(boxes[0][2]), pose)]
    return [SceneObject(f"{name}/{piece}", Box(size), pose @ transform(pos=centre))
            for piece, centre, size in boxes]


def static_objects(cell: Cell, path: str = "") -> tuple[SceneObject, ...]:
    """A cell's static scenery (meshes loaded; ``path`` names the file in errors)."""
    return tuple(SceneObject(p.name, solid(p.shape, path or cell.name), p.pose, p.allow)
                 for p in cell.static)


def cell_objects(cell: Cell, path: str = "") -> tuple[SceneObject, ...]:
    """A cell's obstacles in the description's order: its static scenery, and its spawned
    objects at the poses the description gives them."""
    pieces = {o.name: [o] for o in static_objects(cell, path)}
    for p in cell.spawn:
        pieces[p.name] = wc_object_pieces(p.name, p.wc_class, p.pose, p.scale)
    return tuple(o for name in (cell.order or tuple(pieces)) for o in pieces[name])


def sighting_scale(s: Sighting) -> tuple[float, float, float]:
    """The scale an object was spawned with, from its class and what GetSTA reports: the
    world-axis bounding box of a box of edge lengths ``e`` turned by ``R`` is ``|R| e``, so
    ``e`` is the least-squares solution of ``|R| e = size`` (exact unless the object is
    turned to an axis-symmetric 45 degrees, where it is the best guess)."""
    edges, *_ = np.linalg.lstsq(np.abs(s.pose[:3, :3]), np.asarray(s.size, dtype=float),
                                rcond=None)
    scale = np.maximum(edges / np.asarray(s.wc_class.size), 1e-3)
    return (float(scale[0]), float(scale[1]), float(scale[2]))


def scene_from_sightings(sightings: Sequence[Sighting], cell: Cell | None = None,
                         robot_pose: Array | None = None, name: str = "simulator") -> Scene:
    """The planning Scene of what the simulator reports: the cell's static scenery (when
    given), then each sighted object as its class's boxes, in the base_link of a robot at
    ``robot_pose`` (4x4, z-down world; default: at RobotStart1, the world origin)."""
    base = np.eye(4) if robot_pose is None else robot_pose
    to_base = invert(_FLIP @ base @ _FLIP)  # the REP-103 world -> the robot's base_link
    objects = [SceneObject(o.name, o.shape, to_base @ o.pose, o.allow)
               for o in (static_objects(cell) if cell is not None else ())]
    for s in sightings:
        pose = _FLIP @ invert(base) @ s.pose @ _FLIP
        objects += wc_object_pieces(s.name, s.wc_class, pose, sighting_scale(s))
    return Scene(name, tuple(objects))
