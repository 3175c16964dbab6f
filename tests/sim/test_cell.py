"""One description of the cell, and the planner's model around the simulator's.

The simulator's default world and the planner's ``table`` scene are read from one file: every
static piece MuJoCo holds is the planner's object of that name, the same shape at the same
pose, and the objects the WorldController spawns from the description are the planner's too
(read back from MuJoCo's compiled model, compared point by point). And the learnt KR60's
collision cylinders (``robots/generated/KR60.urdf``, the planner's model) enclose the
simulator's link capsules at any configuration (points sampled on MuJoCo's capsules, tested
against cylinders computed from the URDF file alone), so that a motion planned collision-free
does not touch in the simulator.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from usar_arm.core.cell import load_cell
from usar_arm.core.spatial import FLIP_X, Array, exp_so3, matrix_to_rpy, rpy_to_matrix, transform
from usar_arm.planning.scene import Box, CylinderShape, Mesh, SceneObject
from usar_arm.planning.scene_file import load_scene
from usar_arm.sim import mj
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.robot_spec import builtin_robots
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.sim.world_spec import load_world
from usar_arm.usarsim.world_controller import WorldControllerClient

ROOT = Path(__file__).resolve().parents[2]
FLIP = transform(FLIP_X)


def _geom_pose(world: PhysicsWorld, g: int) -> Array:
    d = world.data
    return transform(d.geom_xmat[g].reshape(3, 3).copy(), d.geom_xpos[g].copy())


def _box_corners(pose: Array, size: np.ndarray) -> np.ndarray:
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    return (pose[:3, :3] @ (signs * np.asarray(size) / 2).T).T + pose[:3, 3]


def _same_points(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """Every point of ``a`` has one of ``b`` within ``tol`` and the other way round."""
    dist = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return bool(dist.min(axis=1).max() < tol and dist.min(axis=0).max() < tol)


def _shape_points(obj: SceneObject) -> np.ndarray:
    """Points that fix the planner object's shape and pose (box corners, cylinder rim ends,
    mesh vertices), in REP-103."""
    s, pose = obj.shape, obj.pose
    if isinstance(s, Box):
        return _box_corners(pose, np.array(s.size))
    if isinstance(s, CylinderShape):
        ends = np.array([[0, 0, -s.length / 2], [0, 0, s.length / 2]])
        return (pose[:3, :3] @ ends.T).T + pose[:3, 3]
    assert isinstance(s, Mesh)
    return (pose[:3, :3] @ s.vertices.T).T + pose[:3, 3]


def _mujoco_points(world: PhysicsWorld, g: int) -> tuple[str, np.ndarray]:
    """The same points of MuJoCo's geom ``g``, back in REP-103."""
    m = world.model
    pose = FLIP @ _geom_pose(world, g)
    kind = int(m.geom_type[g])
    if kind == mj.BOX:
        return "box", _box_corners(pose, 2 * m.geom_size[g])
    if kind == mj.CYLINDER:
        half = m.geom_size[g][1]
        ends = np.array([[0, 0, -half], [0, 0, half]])
        return "cylinder", (pose[:3, :3] @ ends.T).T + pose[:3, 3]
    assert kind == mj.MESH
    mesh = m.geom_dataid[g]
    start, count = m.mesh_vertadr[mesh], m.mesh_vertnum[mesh]
    verts = m.mesh_vert[start:start + count]
    return "mesh", (pose[:3, :3] @ verts.T).T + pose[:3, 3]


def test_the_simulators_scenery_is_the_planners_table_scene() -> None:
    scene = load_scene("table")
    world = PhysicsWorld(cell=load_world().cell)
    m = world.model
    cell_geoms = {mj.id_name(m, "geom", g)[len("cell/"):]: g for g in range(m.ngeom)
                  if mj.id_name(m, "geom", g).startswith("cell/")}
    static = [o for o in scene.objects if o.name in cell_geoms]
    assert sorted(cell_geoms) == sorted(p.name for p in load_cell("table").static)
    assert len(static) == len(cell_geoms) == 8
    for obj in static:
        kind, points = _mujoco_points(world, cell_geoms[obj.name])
        expected = _shape_points(obj)
        assert kind == type(obj.shape).__name__.lower().replace("shape", ""), obj.name
        if isinstance(obj.shape, CylinderShape):
            assert m.geom_size[cell_geoms[obj.name]][0] == pytest.approx(obj.shape.radius)
        if kind == "mesh":  # MuJoCo may drop duplicate vertices and re-centre the rest
            assert _same_points(points, np.unique(expected.round(9), axis=0), 1e-6), obj.name
        else:
            assert _same_points(points, expected, 1e-9), obj.name


def test_the_spawned_part_and_bin_are_the_planners_and_the_bin_is_open() -> None:
    scene = load_scene("table")
    cell = load_cell("table")
    with SimServer(SimOptions(port=0, gravity=False)) as server, \
            WorldControllerClient(port=server.port) as wc:
        for p in cell.spawn:  # the demo's way: CONTROL Create from the description
            zdown = FLIP @ p.pose @ FLIP
            wc.create(p.name, p.wc_class.name, zdown[:3, 3], matrix_to_rpy(zdown[:3, :3]),
                      p.scale, p.physics)
        world = server.world
        m = world.model
        pieces = {mj.id_name(m, "geom", g): g for g in range(m.ngeom)
                  if mj.id_name(m, "geom", g).startswith("wc/")}
        by_object = {o.name: o for o in world.objects.objects.values()}
        for obj in scene.objects:
            owner, _, piece = obj.name.partition("/")
            if owner not in by_object:
                continue
            geom = pieces[f"{by_object[owner].body}/{piece or 'body'}"]
            kind, points = _mujoco_points(world, geom)
            assert kind == "box" and _same_points(points, _shape_points(obj), 1e-6), obj.name
    bin_pieces = [o for o in scene.objects if o.name.startswith("bin/")]
    assert sorted(o.name for o in bin_pieces) == ["bin/floor", "bin/wall_back", "bin/wall_front",
                                                  "bin/wall_left", "bin/wall_right"]
    tops = [float(_shape_points(o)[:, 2].max()) for o in bin_pieces]
    assert max(tops) == pytest.approx(0.90) and min(tops) == pytest.approx(0.715)  # open top
    part = scene.object("part")
    assert float(_shape_points(part)[:, 2].max()) == pytest.approx(0.80)  # the pick


# ------------------------------------------------------------------ the planner's model


def _urdf(path: Path) -> tuple[list[dict], dict[str, list[tuple[Array, float, float]]]]:
    """The URDF's joints (name, type, parent, child, origin, axis) in file order and each
    link's collision cylinders (pose in the link, radius, length), read with ElementTree."""
    root = ET.parse(path).getroot()

    def origin(el: ET.Element | None) -> Array:
        if el is None:
            return np.eye(4)
        xyz = [float(v) for v in el.get("xyz", "0 0 0").split()]
        rpy = [float(v) for v in el.get("rpy", "0 0 0").split()]
        return transform(rpy_to_matrix(rpy), xyz)

    joints = [{"name": j.get("name"), "type": j.get("type"), "parent": j.find("parent").get(
        "link"), "child": j.find("child").get("link"), "origin": origin(j.find("origin")),
        "axis": np.array([float(v) for v in (j.find("axis").get("xyz") if j.find("axis")
                                             is not None else "1 0 0").split()])}
        for j in root.findall("joint")]
    cylinders: dict[str, list[tuple[Array, float, float]]] = {}
    for link in root.findall("link"):
        for c in link.findall("collision"):
            cyl = c.find("geometry/cylinder")
            if cyl is not None:
                cylinders.setdefault(link.get("name", ""), []).append(
                    (origin(c.find("origin")), float(cyl.get("radius", 0)),
                     float(cyl.get("length", 0))))
    return joints, cylinders


def _urdf_link_poses(joints: list[dict], q: np.ndarray) -> dict[str, Array]:
    poses, k = {"base_link": np.eye(4)}, 0
    for j in joints:  # (file order: parents first)
        motion = np.eye(4)
        if j["type"] in ("revolute", "continuous"):
            axis = j["axis"] / np.linalg.norm(j["axis"])
            motion = transform(exp_so3(axis * q[k]))
            k += 1
        elif j["type"] == "prismatic":
            motion = transform(pos=j["axis"] * q[k])
            k += 1
        poses[j["child"]] = poses[j["parent"]] @ j["origin"] @ motion
    return poses


def _inside(points: np.ndarray, cylinders: list[tuple[Array, float, float]],
            pose: Array) -> np.ndarray:
    """Which points (base_link) lie in at least one of a link's cylinders."""
    ok = np.zeros(len(points), dtype=bool)
    for local, radius, length in cylinders:
        frame = pose @ local
        p = (points - frame[:3, 3]) @ frame[:3, :3]
        ok |= (np.hypot(p[:, 0], p[:, 1]) <= radius + 1e-9) & (np.abs(p[:, 2]) <= length / 2)
    return ok


def _capsule_samples(world: PhysicsWorld, g: int, rng: np.random.Generator) -> np.ndarray:
    """Points on the surface of MuJoCo's collision geom ``g`` (a capsule or sphere), world."""
    m = world.model
    pose = _geom_pose(world, g)
    radius = m.geom_size[g][0]
    half = m.geom_size[g][1] if int(m.geom_type[g]) == mj.CAPSULE else 0.0
    n = 200
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    along = rng.uniform(-half, half, size=n)
    local = dirs * radius + np.column_stack([np.zeros(n), np.zeros(n), along])
    ends = np.array([[0, 0, -half], [0, 0, half]])  # the caps' extreme points too
    cap = np.array([0.0, 0.0, radius])
    local = np.vstack([local, ends - cap, ends + cap])
    return (pose[:3, :3] @ local.T).T + pose[:3, 3]


@pytest.mark.parametrize("robot", ["KR60", "Fanuc_M16iB20"])
def test_the_learnt_cylinders_enclose_the_simulators_link_geometry(robot: str) -> None:
    spec = builtin_robots()[f"USARBot.{robot}"]
    act = spec.actuators[0]
    joints, cylinders = _urdf(ROOT / "robots" / "generated" / f"{robot}.urdf")
    world = PhysicsWorld(gravity=False)
    world.add_robot("c1", spec, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    m = world.model
    parts = {jt.child: f"link_{i + 1}" for i, jt in enumerate(act.joints)} | {
        act.body: "base_link"}
    rng = np.random.default_rng(36)
    checked = 0
    for _ in range(25):
        q = np.array([rng.uniform(jt.limit_low, jt.limit_high) for jt in act.joints])
        world.set_joint_values("c1", act.name, q)
        poses = _urdf_link_poses(joints, q)
        for g in range(m.ngeom):
            name = mj.id_name(m, "geom", g)
            if "/collision/" not in name:
                continue
            part = name.split("/")[2]
            link = parts[part]
            world_points = _capsule_samples(world, g, rng)
            points = world_points * (1.0, -1.0, -1.0)  # the base_link (REP-103) at the origin
            inside = _inside(points, cylinders[link], poses[link])
            assert inside.all(), (robot, part, link, q, points[~inside][:3])
            checked += 1
    assert checked >= 25 * 5
