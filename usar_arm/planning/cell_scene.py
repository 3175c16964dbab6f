"""A work cell as a planning Scene: its static scenery, and the WorldController's objects from
the description or from what the simulator says is really there (its GetSTA reply).

An object of a WorldController class becomes its class's boxes (:mod:`usar_arm.core.wc_classes`):
one box named after the object for a solid one, and for an open container its floor and four
walls, named ``<object>/floor``, ``<object>/wall_front``... so a part can be planned *into* it.
"""

from __future__ import annotations

from usar_arm.core.cell import Cell, MeshFile, StaticPiece
from usar_arm.core.errors import FileFormatError
from usar_arm.core.spatial import Array, transform
from usar_arm.core.wc_classes import WcClass
from usar_arm.planning.scene import Box, Mesh, SceneObject, Shape


def _shape(piece: StaticPiece, path: str) -> Shape:
    shape = piece.shape
    if not isinstance(shape, MeshFile):
        return shape
    from usar_arm.urdf.meshes import load_mesh  # trimesh: only when a scene has a mesh

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
    return tuple(SceneObject(p.name, _shape(p, path or cell.name), p.pose, p.allow)
                 for p in cell.static)


def cell_objects(cell: Cell, path: str = "") -> tuple[SceneObject, ...]:
    """A cell's obstacles: its static scenery, then its spawned objects at the poses the
    description gives them."""
    out = list(static_objects(cell, path))
    for placement in cell.spawn:
        out += wc_object_pieces(placement.name, placement.wc_class, placement.pose,
                                placement.scale)
    return tuple(out)
