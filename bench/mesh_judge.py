"""The brute-force judge of the ``robots`` stage: a mesh robot (any URDF) among boxes, cylinders
and spheres.

It shares no code with usar-arm (nor with ``robots_data.py``'s solver-side reading): it parses
the URDF's collision elements with ``xml.etree`` (meshes read by trimesh, STL or DAE, into
python-fcl BVH models; boxes, cylinders and spheres as python-fcl primitives), the SRDF's
disabled pairs, and the obstacles from MoveIt planning-scene YAML text (PyYAML; ROS
quaternions x, y, z, w; cylinders [height, radius]) or from explicit obstacle dicts; forward
kinematics by Pinocchio from the URDF text. Every collision element of a link is its own
object; a pair of links is checked unless the SRDF disables it or they are parts of one rigid
body (links joined by fixed joints only, e.g. the UR5's ``ee_link`` box on ``wrist_3_link``,
which always touch and which example-robot-data's ``ur5.srdf`` does not list); every link
against every obstacle, through python-fcl's dynamic AABB tree broad phase (exact narrow phase
behind it).
"""

from __future__ import annotations

import itertools
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import fcl
import numpy as np
import pinocchio as pin
import trimesh
import yaml
from judge_reading import Carried, pose, quat_matrix, rpy_matrix
from verify import PathJudge, obstacle_geometry

Array = np.ndarray


def _tf(t: Array) -> fcl.Transform:
    return fcl.Transform(np.ascontiguousarray(t[:3, :3]), np.ascontiguousarray(t[:3, 3]))


def _origin(el: ET.Element | None) -> Array:
    if el is None:
        return np.eye(4)
    xyz = [float(v) for v in el.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in el.get("rpy", "0 0 0").split()]
    return pose(rpy_matrix(*rpy), xyz)


def _mesh_bvh(path: str, scale: Array) -> fcl.BVHModel:
    m = trimesh.load(path, force="mesh")
    v = np.asarray(m.vertices, float) * scale
    f = np.asarray(m.faces, np.int64)
    bvh = fcl.BVHModel()
    bvh.beginModel(len(v), len(f))
    bvh.addSubModel(v, f)
    bvh.endModel()
    return bvh


def _geometry(geom: ET.Element, package_paths: dict[str, str]) -> fcl.CollisionGeometry:
    shape = geom[0]
    if shape.tag == "box":
        return fcl.Box(*[float(v) for v in shape.get("size", "").split()])
    if shape.tag == "cylinder":
        return fcl.Cylinder(float(shape.get("radius")), float(shape.get("length")))
    if shape.tag == "sphere":
        return fcl.Sphere(float(shape.get("radius")))
    if shape.tag == "mesh":
        name = shape.get("filename", "")
        for prefix, folder in package_paths.items():
            name = name.replace(f"package://{prefix}/", f"{folder}/")
        name = name.removeprefix("file://")
        scale = np.array([float(v) for v in shape.get("scale", "1 1 1").split()])
        return _mesh_bvh(name, scale)
    raise ValueError(f"unsupported collision geometry <{shape.tag}>")


def srdf_disabled(srdf_text: str | None) -> set[tuple[str, str]]:
    if not srdf_text:
        return set()
    root = ET.fromstring(srdf_text)
    return {tuple(sorted((e.get("link1"), e.get("link2"))))  # type: ignore[misc]
            for e in root.iter("disable_collisions")}


def _ros_pose(p: dict[str, Any] | None) -> Array:
    """4x4 of a ROS pose (position, orientation x y z w); the identity for None."""
    if p is None:
        return np.eye(4)
    x, y, z, w = (float(v) for v in p["orientation"])
    return pose(quat_matrix(w, x, y, z), p["position"])


def obstacles_from_scene_yaml(text: str) -> list[tuple[fcl.CollisionGeometry, Array]]:
    """(geometry, 4x4 pose) of every primitive of a MoveIt planning scene's world, in the
    scene's frame: the object's own ``pose`` (MoveIt's CollisionObject.pose; identity when
    absent) times the primitive's pose relative to it."""
    doc = yaml.safe_load(text)
    out = []
    for obj in doc["world"]["collision_objects"]:
        at = _ros_pose(obj.get("pose"))
        for prim, p in zip(obj.get("primitives", []), obj.get("primitive_poses", []),
                           strict=True):
            d = [float(v) for v in prim["dimensions"]]
            t = at @ _ros_pose(p)
            if prim["type"] == "box":
                g = fcl.Box(*d[:3])
            elif prim["type"] == "cylinder":
                g = fcl.Cylinder(d[1], d[0])
            elif prim["type"] == "sphere":
                g = fcl.Sphere(d[0])
            else:
                raise ValueError(f"unsupported primitive {prim['type']!r}")
            out.append((g, t))
    return out


def obstacles_from_dicts(items: list[dict[str, Any]]) -> list[tuple[fcl.CollisionGeometry, Array]]:
    """(geometry, pose) of obstacles given as dicts (tests): type box/cylinder/sphere."""
    out = []
    for d in items:
        t = pose(quat_matrix(*d.get("quat_wxyz", [1, 0, 0, 0])), d["xyz"])
        g = (fcl.Box(*d["size"]) if d["type"] == "box" else
             fcl.Cylinder(d["radius"], d["length"]) if d["type"] == "cylinder" else
             fcl.Sphere(d["radius"]))
        out.append((g, t))
    return out


def _parent_joint(frame: Any) -> int:
    return int(frame.parentJoint if hasattr(frame, "parentJoint") else frame.parent)


class MeshRobot:
    """The robot's collision elements and kinematics, as the judge reads them."""

    def __init__(self, urdf_path: str | Path, srdf_path: str | Path | None,
                 joint_names: list[str], package_paths: dict[str, str] | None = None):
        text = Path(urdf_path).read_text(encoding="utf-8")
        self.model = pin.buildModelFromXML(text)
        self.data = self.model.createData()
        self.index = [self.model.joints[self.model.getJointId(n)].idx_q for n in joint_names]
        root = ET.fromstring(text)
        limits = {j.get("name"): j.find("limit") for j in root.findall("joint")}
        self.lower = np.array([float(limits[n].get("lower")) for n in joint_names])  # type: ignore[union-attr]
        self.upper = np.array([float(limits[n].get("upper")) for n in joint_names])  # type: ignore[union-attr]
        self.elements: list[tuple[str, Array, fcl.CollisionGeometry]] = []
        for link in root.findall("link"):
            for col in link.findall("collision"):
                geom = col.find("geometry")
                if geom is None or not len(geom):
                    continue
                self.elements.append((link.get("name", ""), _origin(col.find("origin")),
                                      _geometry(geom, package_paths or {})))
        self.frame_of = {name: self.model.getFrameId(name) for name, _, _ in self.elements}
        disabled = srdf_disabled(Path(srdf_path).read_text() if srdf_path else None)
        body = {name: _parent_joint(self.model.frames[f]) for name, f in self.frame_of.items()}
        self.self_pairs = [(i, j) for (i, a), (j, b) in itertools.combinations(
            enumerate(e[0] for e in self.elements), 2)
            if a != b and body[a] != body[b] and tuple(sorted((a, b))) not in disabled]

    def update(self, q: Array) -> None:
        full = pin.neutral(self.model)
        full[self.index] = q
        pin.framesForwardKinematics(self.model, self.data, full)

    def frame(self, name: str) -> Array:
        return np.array(self.data.oMf[self.model.getFrameId(name)].homogeneous)

    def element_poses(self, q: Array) -> list[Array]:
        self.update(np.asarray(q, float))
        return [np.array(self.data.oMf[self.frame_of[link]].homogeneous) @ origin
                for link, origin, _ in self.elements]


class MeshJudge(PathJudge):
    """Brute-force collision check of a :class:`MeshRobot` among obstacles, carrying
    ``carried`` objects (each at its link's pose times its grasp, checked against every
    collision element but those of its own link and its touch links, the other carried objects
    unless one holds or may touch the other, and every obstacle)."""

    def __init__(self, robot: MeshRobot, obstacles: list[tuple[fcl.CollisionGeometry, Array]],
                 carried: list[Carried] | None = None):
        self.robot = robot
        self.carried = list(carried or [])
        self.held = [fcl.CollisionObject(obstacle_geometry(c.body), fcl.Transform())
                     for c in self.carried]
        links = [e[0] for e in robot.elements]
        self.held_pairs = [(k, i) for k, c in enumerate(self.carried)
                           for i, name in enumerate(links)
                           if name != c.link and name not in c.touch_links]
        self.held_each = [(k, m) for k, m in itertools.combinations(range(len(self.carried)), 2)
                          if not {self.carried[k].link, *self.carried[k].touch_links}
                          & {self.carried[m].name}
                          and not {self.carried[m].link, *self.carried[m].touch_links}
                          & {self.carried[k].name}]
        self.parts = [fcl.CollisionObject(g, fcl.Transform()) for _, _, g in robot.elements]
        self.env = [fcl.CollisionObject(g, _tf(t)) for g, t in obstacles]
        self.env_manager = fcl.DynamicAABBTreeCollisionManager()
        if self.env:
            self.env_manager.registerObjects(self.env)
            self.env_manager.setup()
        self.robot_manager = fcl.DynamicAABBTreeCollisionManager()
        self.robot_manager.registerObjects(self.parts)
        self.robot_manager.setup()
        self.request = fcl.CollisionRequest()

    def collides(self, q: Array) -> bool:
        for obj, t in zip(self.parts, self.robot.element_poses(q), strict=True):
            obj.setTransform(_tf(t))
        for i, j in self.robot.self_pairs:
            if fcl.collide(self.parts[i], self.parts[j], self.request, fcl.CollisionResult()):
                return True
        if self.carried and self._held_collides():
            return True
        if not self.env:
            return False
        self.robot_manager.update()
        data = fcl.CollisionData(self.request, fcl.CollisionResult())
        self.robot_manager.collide(self.env_manager, data, fcl.defaultCollisionCallback)
        return bool(data.result.is_collision)

    def _held_collides(self) -> bool:
        """True when a carried object touches what it may not (after the robot was placed)."""
        frames: dict[str, Array] = {}
        for obj, c in zip(self.held, self.carried, strict=True):
            base = frames[c.link] if c.link in frames else self.robot.frame(c.link)
            frames[c.name] = base @ c.body.pose
            obj.setTransform(_tf(frames[c.name]))
        others = [(self.held[k], self.parts[i]) for k, i in self.held_pairs]
        others += [(self.held[k], self.held[m]) for k, m in self.held_each]
        others += [(h, e) for h in self.held for e in self.env]
        return any(fcl.collide(a, b, self.request, fcl.CollisionResult()) for a, b in others)

    def inside(self, q: Array, slack: float = 1e-6) -> bool:
        return bool(np.all(q >= self.robot.lower - slack) and np.all(q <= self.robot.upper
                                                                     + slack))


def rotation_angle(a: Array, b: Array) -> float:
    """Angle (rad) between two rotations, accurate near 0."""
    return 2.0 * float(np.arcsin(min(1.0, float(np.linalg.norm(a - b)) / np.sqrt(8.0))))
