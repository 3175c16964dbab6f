"""What touches what in the simulator's world, and the world's static scenery.

Contact bits (MuJoCo collides two geoms when one's ``contype`` shares a bit with the other's
``conaffinity``): the scenery and the WorldController's objects are touched by everything that
moves; an arm's links and the tool on its tool changer touch the scenery and the objects, and
the arm's own links and tool touch each other through explicit pairs (:mod:`.arm_bodies`), but
one robot's links and tool do not touch another robot's (the simulator serves many robots
spawned at one start, as UDK's load clients do; a deliberate difference, docs/simulator.md); a
dropped tool is touched by every link and tool; vehicles touch only the scenery and objects. The
scenery is the floor (a plane at ``floor_z``, z down), a world file's boxes, and a work cell's
static pieces (:mod:`usar_arm.core.cell`, REP-103, converted here once to the z-down world).
"""

from __future__ import annotations

from collections.abc import Sequence

from usar_arm.core.cell import MeshFile, StaticPiece
from usar_arm.core.shapes import Box, CylinderShape, Sphere
from usar_arm.core.spatial import FLIP_X, Array, quat_from_matrix, rpy_to_matrix, transform
from usar_arm.core.world_file import SceneryBox
from usar_arm.sim import mj

VEHICLE_BIT = 1
"""Contact type of a vehicle's chassis and wheels."""
OBJECT_BIT = 2
"""Contact type of a WorldController object."""
LINK_BIT = 4
"""Contact type of an arm link."""
TOOL_BIT = 8
"""Contact type of a tool."""
SCENERY_AFFINITY = VEHICLE_BIT | OBJECT_BIT | LINK_BIT | TOOL_BIT
"""The scenery's affinity: everything that moves touches it."""
OBJECT_AFFINITY = SCENERY_AFFINITY
"""A WorldController object's affinity: everything that moves touches it too."""
LINK_AFFINITY = OBJECT_BIT
"""An arm link's affinity (besides the scenery's and the objects', which reach it): objects."""
HELD_TOOL_AFFINITY = OBJECT_BIT
"""The affinity of a tool on a tool changer: objects (the scenery's reaches it)."""
FREE_TOOL_AFFINITY = OBJECT_BIT | LINK_BIT | TOOL_BIT
"""The affinity of a dropped tool: every link and tool touches it."""
FLOOR = "floor"
"""The floor plane's geom name."""
CELL_PREFIX = "cell/"
"""The prefix of a cell's static geoms (``cell/table_top``); the rest of the name is the
piece's."""
BOX_PREFIX = "scenery/"
"""The prefix of a world file's boxes (``scenery/3/pillar``)."""


def quat(rot: Array) -> list[float]:
    """MuJoCo's (w, x, y, z) of a rotation matrix."""
    return [float(v) for v in quat_from_matrix(rot)]


def cell_pose_zdown(pose: Array) -> Array:
    """A cell piece's pose in the z-down world: the REP-103 pose turned by pi about x (the
    USARSim axes), the piece's own axes carried along (so its shape is the same set of
    points)."""
    out: Array = transform(FLIP_X) @ pose
    return out


def add_scenery(spec: mj.Spec, boxes: Sequence[SceneryBox], floor_z: float,
                pieces: Sequence[StaticPiece] = ()) -> None:
    """The floor (a plane facing up, i.e. toward -z: its normal, +z, turned over about x),
    the world file's boxes and a cell's static pieces, all static and touched by everything
    that moves."""
    world = spec.worldbody
    world.add_geom(name=FLOOR, type=mj.PLANE, size=[0.0, 0.0, 1.0],
                   pos=[0.0, 0.0, floor_z], quat=[0.0, 1.0, 0.0, 0.0],
                   contype=0, conaffinity=SCENERY_AFFINITY)
    for i, box in enumerate(boxes):
        world.add_geom(name=f"{BOX_PREFIX}{i}/{box.name}", type=mj.BOX,
                       size=list(box.half), pos=list(box.center),
                       quat=quat(rpy_to_matrix((0.0, 0.0, box.yaw))),
                       contype=0, conaffinity=SCENERY_AFFINITY)
    for piece in pieces:
        pose = cell_pose_zdown(piece.pose)
        where = {"name": f"{CELL_PREFIX}{piece.name}", "pos": pose[:3, 3].tolist(),
                 "quat": quat(pose[:3, :3]), "contype": 0, "conaffinity": SCENERY_AFFINITY}
        shape = piece.shape
        if isinstance(shape, Box):
            world.add_geom(type=mj.BOX, size=[s / 2 for s in shape.size], **where)
        elif isinstance(shape, CylinderShape):
            world.add_geom(type=mj.CYLINDER, size=[shape.radius, shape.length / 2, 0.0], **where)
        elif isinstance(shape, Sphere):
            world.add_geom(type=mj.SPHERE, size=[shape.radius, 0.0, 0.0], **where)
        else:
            add_mesh_geom(spec, shape, where)


def add_mesh_geom(spec: mj.Spec, shape: MeshFile, where: dict[str, object]) -> None:
    """A static mesh geom (MuJoCo collides with its convex hull, as the planner does with a
    mesh it cannot split)."""
    name = str(where["name"])
    spec.add_mesh(name=name, file=str(shape.path), scale=[shape.scale] * 3)
    spec.worldbody.add_geom(type=mj.MESH, meshname=name, **where)
