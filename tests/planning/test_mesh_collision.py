"""Collision checking of an arm made of meshes, boxes, spheres, capsules and cylinders (several
elements on a link, concave meshes, a scaled mesh) agrees with a brute-force judge written here:
its own URDF parsing and forward kinematics, its own python-fcl shapes from the mesh files,
every pair tested. And the bounding cylinders the compiled verdicts use hold every vertex."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import fcl
import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from usar_arm.core.shapes import Box, Capsule, Mesh, Sphere
from usar_arm.planning.element_fit import bounding_cylinder
from usar_arm.planning.robot import robot_from_files
from usar_arm.planning.scene import Scene, SceneObject

from ..urdf.mesh_robot import DISABLED, PACKAGE, write_robot

CONFIGURATIONS = 3000


def _child(el: ET.Element, tag: str) -> ET.Element:
    found = el.find(tag)
    assert found is not None, f"<{el.tag}> has no <{tag}>"
    return found


class Judge:
    """Every link's collision elements as python-fcl objects, placed by this class's own
    forward kinematics of the URDF file; contacts by testing every pair."""

    def __init__(self, urdf: Path, package: Path, obstacles: list[tuple[str, object, np.ndarray]]):
        root = ET.parse(urdf).getroot()
        self.elements: list[tuple[str, fcl.CollisionObject, np.ndarray]] = []
        for link in root.findall("link"):
            for col in link.findall("collision"):
                geometry = self._geometry(_child(col, "geometry"), package)
                self.elements.append((link.get("name", ""), fcl.CollisionObject(geometry),
                                      self._origin(col.find("origin"))))
        self.joints = [(j.get("name", ""), j.get("type", ""), _child(j, "parent").get("link", ""),
                        _child(j, "child").get("link", ""), self._origin(j.find("origin")),
                        np.array([float(v) for v in _child(j, "axis").get("xyz", "").split()]
                                 if j.find("axis") is not None else [1.0, 0.0, 0.0]))
                       for j in root.findall("joint")]
        self.obstacles = [(name, fcl.CollisionObject(g, fcl.Transform(p[:3, :3], p[:3, 3])))
                          for name, g, p in obstacles]

    @staticmethod
    def _origin(el: ET.Element | None) -> np.ndarray:
        if el is None:
            return np.eye(4)
        xyz = [float(v) for v in el.get("xyz", "0 0 0").split()]
        r, p, y = (float(v) for v in el.get("rpy", "0 0 0").split())
        m = trimesh.transformations.euler_matrix(r, p, y, "sxyz")
        m[:3, 3] = xyz
        return m

    @staticmethod
    def _geometry(g: ET.Element, package: Path) -> fcl.CollisionGeometry:
        shape = g[0]
        if shape.tag == "mesh":
            name = shape.get("filename", "")
            file = package / name.split(f"package://{PACKAGE}/")[-1].split(
                f"{PACKAGE}/")[-1]
            mesh: Any = trimesh.load(file, force="mesh")
            scale = [float(v) for v in shape.get("scale", "1 1 1").split()]
            model = fcl.BVHModel()
            model.beginModel(len(mesh.vertices), len(mesh.faces))
            model.addSubModel(np.asarray(mesh.vertices) * scale, np.asarray(mesh.faces))
            model.endModel()
            return model
        size = {k: float(v) if k != "size" else [float(x) for x in v.split()]
                for k, v in shape.attrib.items()}
        return {"box": lambda: fcl.Box(*size["size"]),  # type: ignore[misc]
                "sphere": lambda: fcl.Sphere(size["radius"]),
                "cylinder": lambda: fcl.Cylinder(size["radius"], size["length"]),
                "capsule": lambda: fcl.Capsule(size["radius"], size["length"])}[shape.tag]()

    def link_poses(self, values: dict[str, float]) -> dict[str, np.ndarray]:
        poses = {"base_link": np.eye(4)}
        for name, kind, parent, child, origin, axis in self.joints:
            q = values.get(name, 0.0)
            motion = np.eye(4)
            if kind in ("revolute", "continuous"):
                motion = trimesh.transformations.rotation_matrix(q, axis)
            elif kind == "prismatic":
                motion[:3, 3] = axis * q
            poses[child] = poses[parent] @ origin @ motion
        return poses

    def contacts(self, values: dict[str, float]) -> set[tuple[str, str]]:
        poses = self.link_poses(values)
        for link, obj, local in self.elements:
            m = poses[link] @ local
            obj.setTransform(fcl.Transform(m[:3, :3], m[:3, 3]))
        bodies = [(link, obj) for link, obj, _ in self.elements] + self.obstacles
        found = set()
        for i, (a, oa) in enumerate(bodies):
            for b, ob in bodies[i + 1:]:
                key = (a, b) if a <= b else (b, a)
                if a == b or key in DISABLED or key in found:
                    continue
                if fcl.collide(oa, ob, fcl.CollisionRequest(), fcl.CollisionResult()):
                    found.add(key)
        return found


def _pose(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def test_contacts_agree_with_an_independent_brute_force_judge(tmp_path: Path) -> None:
    urdf, srdf = write_robot(tmp_path)
    robot = robot_from_files(urdf, srdf)
    table, ball = _pose(0.0, 0.0, -0.02), _pose(0.25, 0.1, 0.45)
    scene = Scene("test", (SceneObject("table", Box((1.0, 1.0, 0.04)), table, ("base_link",)),
                           SceneObject("ball", Sphere(0.08), ball)))
    world = robot.collision_world(scene)
    judge = Judge(urdf, urdf.parents[1], [("ball", fcl.Sphere(0.08), ball),
                                          ("table", fcl.Box(1.0, 1.0, 0.04), table)])
    judge_disabled = {("base_link", "table")}
    rng = np.random.default_rng(7)
    qs = rng.uniform(robot.chain.lower(), robot.chain.upper(), (CONFIGURATIONS, 4))
    ours = world.contacts_many(qs)
    hits = world.in_collision_many(qs)
    missed = invented = 0
    for q, found, hit in zip(qs, ours, hits, strict=True):
        values = dict(zip(robot.chain.joint_names, q, strict=True))
        values["finger_l_joint"] = values["finger_r_joint"] = 0.02  # held mid-range (mimic)
        truth = judge.contacts(values) - judge_disabled
        missed += len(truth - set(found))
        invented += len(set(found) - truth)
        assert bool(hit) == bool(truth)
    assert (missed, invented) == (0, 0)
    in_contact = sum(bool(f) for f in ours)
    assert 0.05 * CONFIGURATIONS < in_contact < 0.95 * CONFIGURATIONS  # both kinds were seen


finite = st.floats(-10.0, 10.0, allow_nan=False, width=64)


@settings(max_examples=200, deadline=None)
@given(points=arrays(np.float64, st.tuples(st.integers(1, 40), st.just(3)), elements=finite),
       stretch=arrays(np.float64, 3, elements=st.floats(1e-3, 50.0)))
def test_the_bounding_cylinder_of_a_mesh_holds_every_vertex(points: np.ndarray,
                                                             stretch: np.ndarray) -> None:
    vertices = points * stretch
    fit = bounding_cylinder(Mesh(vertices, np.zeros((0, 3), np.int64)))
    local = (vertices - fit.frame[:3, 3]) @ fit.frame[:3, :3]
    assert np.all(np.hypot(local[:, 0], local[:, 1]) <= fit.radius)
    assert np.all(np.abs(local[:, 2]) <= fit.half)
    assert not fit.exact


@settings(max_examples=100, deadline=None)
@given(size=st.tuples(*[st.floats(1e-3, 5.0)] * 3))
def test_the_bounding_cylinder_of_a_box_holds_its_corners(size: tuple[float, float, float]
                                                          ) -> None:
    fit = bounding_cylinder(Box(size))
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    local = (corners * np.asarray(size) / 2 - fit.frame[:3, 3]) @ fit.frame[:3, :3]
    assert np.all(np.hypot(local[:, 0], local[:, 1]) <= fit.radius)
    assert np.all(np.abs(local[:, 2]) <= fit.half)


@pytest.mark.parametrize("shape", [Sphere(0.1), Capsule(0.05, 0.3)])
def test_spheres_and_capsules_keep_their_contact_proofs(shape: Sphere | Capsule) -> None:
    """Their bounding cylinder's inner balls are the shape's own (radius, half-length m)."""
    fit = bounding_cylinder(shape)
    assert fit.exact and fit.radius == shape.radius
    assert fit.half - fit.radius == pytest.approx(shape.length / 2 if isinstance(shape, Capsule)
                                                 else 0.0, abs=1e-15)


def test_a_segment_walk_of_a_mesh_arm_answers_as_checking_every_configuration(
        tmp_path: Path) -> None:
    """The walk's skips rest on lever arms of the bounding cylinders: still no contact missed
    between the configurations it does not check."""
    urdf, srdf = write_robot(tmp_path)
    robot = robot_from_files(urdf, srdf)
    world = robot.collision_world()
    rng = np.random.default_rng(3)
    lo, hi = robot.chain.lower(), robot.chain.upper()
    blocked = 0
    for _ in range(150):
        a = rng.uniform(lo, hi)
        b = np.clip(a + rng.normal(0.0, 0.6, 4), lo, hi)
        every = world.in_collision_many(np.linspace(a, b, 41))
        blocked += bool(every.any())
        assert world.segment_free(a, b, 40) == (not every.any())
    assert 5 < blocked < 145


def test_a_segment_among_obstacles_answers_as_checking_every_configuration(
        tmp_path: Path) -> None:
    """Long segments among obstacles, which the walk checks coarse to fine: the same answer as
    checking all."""
    urdf, srdf = write_robot(tmp_path)
    robot = robot_from_files(urdf, srdf)
    scene = Scene("test", (SceneObject("table", Box((1.0, 1.0, 0.04)), _pose(0.0, 0.0, -0.02),
                                       ("base_link",)),
                           SceneObject("ball", Sphere(0.08), _pose(0.25, 0.1, 0.45))))
    world = robot.collision_world(scene)
    rng = np.random.default_rng(5)
    lo, hi = robot.chain.lower(), robot.chain.upper()
    steps = 101
    blocked = 0
    for _ in range(150):
        a = rng.uniform(lo, hi)
        b = np.clip(a + rng.normal(0.0, 0.4, 4), lo, hi)
        every = world.in_collision_many(np.linspace(a, b, steps + 1))
        blocked += bool(every.any())
        assert world.segment_free(a, b, steps) == (not every.any())
    assert 15 < blocked < 135


def test_threads_querying_one_world_get_the_answers_of_one_thread(tmp_path: Path) -> None:
    """The single-query path hands FCL its poses and verdicts in arrays of the calling thread's
    own (the kernels release the GIL), so concurrent queries do not see each other's."""
    from concurrent.futures import ThreadPoolExecutor

    urdf, srdf = write_robot(tmp_path)
    robot = robot_from_files(urdf, srdf)
    scene = Scene("test", (SceneObject("ball", Sphere(0.08), _pose(0.25, 0.1, 0.45)),))
    world = robot.collision_world(scene)
    qs = np.random.default_rng(11).uniform(robot.chain.lower(), robot.chain.upper(), (3000, 4))
    alone = [world.in_collision(q) for q in qs]
    with ThreadPoolExecutor(8) as pool:
        together = list(pool.map(world.in_collision, qs, chunksize=1))
    assert together == alone and 0 < sum(alone) < len(alone)
