"""The correctness checks every solver's answers go through, ours as much as the peers'.

Nothing here imports ``usar_arm``: the judge reads the URDF, the SRDF and the scene's YAML file
itself (``judge_reading.py``), builds its own python-fcl primitives and places them
by Pinocchio's forward kinematics of the URDF text.

* IK: forward kinematics of the answer against the target pose, and the joint limits.
* Collision: :class:`Judge` checks every pair the SRDF and the scene leave enabled with
  python-fcl's default request. In scenes of up to :data:`EVERY_PAIR_UP_TO` obstacles every
  pair goes to FCL; in larger ones (the 100 and 1,000 box scenes) an exact sphere test first
  skips pairs whose bounding spheres (a box: its exact distance to the link's bounding sphere)
  are apart, which cannot touch.
* Paths: start and goal, limits, and every configuration along every segment at most
  :data:`PATH_STEP` apart (joint units) checked by the judge.
* Trajectories: end points, velocity and acceleration (finite differences of the samples)
  against the limits, and the samples densified to :data:`PATH_STEP` checked by the judge.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
import pinocchio as pin
from judge_reading import (
    Carried,
    JudgedRobot,
    Obstacle,
    pose,
    quat_matrix,
    read_attached,
    scene_obstacles,
)

Array = np.ndarray

PATH_STEP = 0.005
"""rad or m: largest joint change between two configurations the judge checks on a path (half
our planner's edge resolution, so the judge also looks between our planner's checks)."""
EVERY_PAIR_UP_TO = 64
"""Scenes with at most this many obstacles send every enabled pair to FCL."""
LIMIT_SLACK = 1e-6
"""rad or m beyond a joint limit still accepted (TRAC-IK keeps limits as float32)."""
VELOCITY_SLACK = 1.02
ACCELERATION_SLACK = 1.10
"""Allowed ratio of finite-difference velocity / acceleration to the limit (100 Hz samples)."""


def _tf(t: Array) -> fcl.Transform:
    return fcl.Transform(np.ascontiguousarray(t[:3, :3]), np.ascontiguousarray(t[:3, 3]))


def obstacle_geometry(o: Obstacle) -> fcl.CollisionGeometry:
    """The judge's own python-fcl primitive of an obstacle, in the obstacle's frame (m)."""
    p = o.params
    if o.kind == "box":
        return fcl.Box(*p["size"])
    if o.kind == "cylinder":
        return fcl.Cylinder(p["radius"], p["length"])
    if o.kind == "sphere":
        return fcl.Sphere(p["radius"])
    mesh = fcl.BVHModel()
    mesh.beginModel(len(p["vertices"]), len(p["faces"]))
    mesh.addSubModel(p["vertices"], p["faces"])
    mesh.endModel()
    return mesh


class Kinematics:
    """Pinocchio forward kinematics of the URDF text, with joint values in the order of
    ``joint_names`` (the problem file's), whatever order Pinocchio keeps them in."""

    def __init__(self, robot: JudgedRobot, joint_names: list[str]):
        self.model = pin.buildModelFromXML(robot.urdf)
        self.data = self.model.createData()
        self.index = [self.model.joints[self.model.getJointId(n)].idx_q for n in joint_names]
        by_name = dict(zip(robot.joints, zip(robot.lower, robot.upper, strict=True),
                           strict=True))
        self.lower = np.array([by_name[n][0] for n in joint_names])
        self.upper = np.array([by_name[n][1] for n in joint_names])

    def update(self, q: Array) -> None:
        full = pin.neutral(self.model)
        full[self.index] = q
        pin.framesForwardKinematics(self.model, self.data, full)

    def frame(self, name: str) -> Array:
        """The 4x4 world pose of frame ``name`` after :meth:`update`."""
        return np.array(self.data.oMf[self.model.getFrameId(name)].homogeneous)

    def inside(self, q: Array) -> bool:
        """Every joint value of ``q`` (N, n or n) within its limits (plus the slack)."""
        return bool(np.all(q >= self.lower - LIMIT_SLACK) and np.all(q <= self.upper
                                                                     + LIMIT_SLACK))


class PathJudge:
    """A brute-force judge's answers over many configurations and along a path, from its
    ``collides(q)`` (the cylinder judge here, the mesh judge in ``mesh_judge.py``)."""

    def collides(self, q: Array) -> bool:
        raise NotImplementedError

    def colliding(self, qs: Array, stop_at_first: bool = False) -> Array:
        """True where a configuration (N, n) has a contact in any enabled pair."""
        qs = np.atleast_2d(np.asarray(qs, float))
        out = np.zeros(len(qs), dtype=bool)
        for n, q in enumerate(qs):
            out[n] = self.collides(q)
            if out[n] and stop_at_first:
                break
        return out

    def path_free(self, path: Array, step: float = PATH_STEP) -> bool:
        """Every configuration along the polyline ``path`` (k, n), at most ``step`` apart per
        joint, is free."""
        return not self.colliding(densify(np.asarray(path, float), step),
                                  stop_at_first=True).any()


class Judge(PathJudge):
    """Brute-force collision check of one robot in one scene (python-fcl).

    Args:
        robot: the URDF's cylinders and the SRDF's disabled pairs, as the judge read them.
        obstacles: the scene's; an obstacle's ``allow`` exempts those links from it.
        joint_names: the order of the joint values the judge is given.
        carried: objects fixed to links (each placed at its link's pose times its grasp):
            checked against every link but its own and its touch links, every other carried
            object, and every obstacle; an obstacle of a carried object's name is that object
            and is not checked.
    """

    def __init__(self, robot: JudgedRobot, obstacles: list[Obstacle], joint_names: list[str],
                 carried: list[Carried] | None = None):
        self.carried = list(carried or [])
        names = {c.name for c in self.carried}
        obstacles = [o for o in obstacles if o.name not in names]
        self.kin = Kinematics(robot, joint_names)
        cyl = robot.cylinders
        self.links = [c.link for c in cyl]
        self.local = np.array([c.origin for c in cyl]).reshape(-1, 4, 4)
        self.half = np.array([c.length / 2 for c in cyl])
        self.radius = np.array([c.radius for c in cyl])
        self.robot_objects = [fcl.CollisionObject(fcl.Cylinder(c.radius, c.length),
                                                  fcl.Transform()) for c in cyl]
        self.bound = np.hypot(self.radius, self.half)
        self.objects = [fcl.CollisionObject(obstacle_geometry(o), _tf(o.pose)) for o in obstacles]
        self.obstacles = obstacles
        self.centre = np.array([o.pose[:3, 3] for o in obstacles]).reshape(-1, 3)
        self.reach = np.array([o.bounding_radius() for o in obstacles])
        n = len(cyl)
        self.rr = [(i, j) for i, j in itertools.combinations(range(n), 2)
                   if self.links[i] != self.links[j]  # (a link's elements never collide)
                   and (min(self.links[i], self.links[j]), max(self.links[i], self.links[j]))
                   not in robot.disabled]
        self.rs = [(i, k) for i in range(n) for k, o in enumerate(obstacles)
                   if self.links[i] not in o.allow]
        self.every_pair = len(obstacles) <= EVERY_PAIR_UP_TO
        self.enabled = np.zeros((n, len(obstacles)), dtype=bool)
        for i, k in self.rs:
            self.enabled[i, k] = True
        self.is_box = np.array([o.kind == "box" for o in obstacles], dtype=bool)
        self.box_rot = np.array([o.pose[:3, :3] for o in obstacles]).reshape(-1, 3, 3)
        self.box_half = np.array([np.asarray(o.params["size"]) / 2 if o.kind == "box"
                                  else np.zeros(3) for o in obstacles]).reshape(-1, 3)
        self.request = fcl.CollisionRequest()
        self.carried_objects = [fcl.CollisionObject(obstacle_geometry(c.body), fcl.Transform())
                                for c in self.carried]
        self.carried_pairs = [(k, ("robot", i)) for k, c in enumerate(self.carried)
                              for i in range(n) if self.links[i] != c.link
                              and self.links[i] not in c.touch_links]
        self.carried_pairs += [(k, ("carried", m)) for k, m in itertools.combinations(
            range(len(self.carried)), 2) if not self._holds(k, m)]
        self.carried_pairs += [(k, ("scene", j)) for k, c in enumerate(self.carried)
                               for j, o in enumerate(obstacles) if c.name not in o.allow]

    def _holds(self, k: int, m: int) -> bool:
        """Carried objects k and m may touch: one is fixed to, or a touch link of, the other."""
        a, b = self.carried[k], self.carried[m]
        return a.link == b.name or b.link == a.name or a.name in b.touch_links \
            or b.name in a.touch_links

    @classmethod
    def for_scene(cls, spec: dict[str, Any], scene: str) -> Judge:
        """The judge of a problem file's robot (``urdf``, ``srdf``, ``joint_names``) in its
        scene ``scene`` (read from the scene's YAML file, ``scene_files``), carrying the
        file's ``attached`` objects when it has them."""
        robot = JudgedRobot.from_files(spec["urdf"], spec.get("srdf"))
        return cls(robot, scene_obstacles(spec, scene), list(spec["joint_names"]),
                   read_attached(spec.get("attached", [])))

    def poses(self, q: Array) -> Array:
        """World poses (L, 4, 4) of the link cylinders at one configuration."""
        self.kin.update(q)
        return np.array([self.kin.frame(name) for name in self.links]) @ self.local

    def capsules(self, qs: Array) -> tuple[Array, Array, Array]:
        """Every link cylinder at every configuration as a capsule: axis ends a, b (M, 3) and
        radius (M,) (a capsule contains its cylinder)."""
        poses = np.array([self.poses(q) for q in np.atleast_2d(np.asarray(qs, float))])
        axis = poses[..., :3, 2] * self.half[:, None]
        centre = poses[..., :3, 3]
        radius = np.broadcast_to(self.radius, centre.shape[:2])
        return ((centre - axis).reshape(-1, 3), (centre + axis).reshape(-1, 3),
                np.asarray(radius).reshape(-1))

    def _near(self, centres: Array) -> list[tuple[int, int]]:
        """The enabled link-obstacle pairs that may touch, given the link cylinders' centres
        (L, 3): a link's bounding sphere reaches the obstacle (exactly for boxes, by bounding
        spheres otherwise). Conservative: a pair left out cannot touch."""
        d = centres[:, None, :] - self.centre[None, :, :]                      # (L, S, 3)
        local = np.einsum("sji,lsj->lsi", self.box_rot, d)                      # R^T d
        box_gap = np.linalg.norm(local - np.clip(local, -self.box_half, self.box_half), axis=2)
        sphere_gap = np.linalg.norm(d, axis=2) - self.reach
        gap = np.where(self.is_box, box_gap, sphere_gap)
        near = (gap <= self.bound[:, None] + 1e-9) & self.enabled
        return [(int(i), int(k)) for i, k in zip(*np.nonzero(near), strict=True)]

    def collides(self, q: Array) -> bool:
        """True when any enabled pair is in contact at ``q`` (n,)."""
        poses = self.poses(np.asarray(q, float))
        for i, placed in enumerate(self.robot_objects):
            placed.setTransform(_tf(poses[i]))
        for i, j in self.rr:
            if fcl.collide(self.robot_objects[i], self.robot_objects[j], self.request,
                           fcl.CollisionResult()) > 0:
                return True
        for i, k in (self.rs if self.every_pair else self._near(poses[:, :3, 3])):
            if fcl.collide(self.robot_objects[i], self.objects[k], self.request,
                           fcl.CollisionResult()) > 0:
                return True
        return self._carried_collides()

    def _carried_collides(self) -> bool:
        """True when a carried object touches what it may not (after :meth:`poses`)."""
        frames: dict[str, Array] = {}
        for obj, c in zip(self.carried_objects, self.carried, strict=True):
            base = frames[c.link] if c.link in frames else self.kin.frame(c.link)
            frames[c.name] = base @ c.body.pose
            obj.setTransform(_tf(frames[c.name]))
        groups = {"robot": self.robot_objects, "carried": self.carried_objects,
                  "scene": self.objects}
        for k, (group, j) in self.carried_pairs:
            if fcl.collide(self.carried_objects[k], groups[group][j], self.request,
                           fcl.CollisionResult()) > 0:
                return True
        return False



def densify(path: Array, step: float) -> Array:
    """The polyline's vertices and points between them at most ``step`` apart per joint."""
    if len(path) < 2:
        return path
    parts = []
    for a, b in itertools.pairwise(path):
        k = max(1, math.ceil(float(np.max(np.abs(b - a))) / step))
        parts.append(a + (b - a) * np.linspace(0.0, 1.0, k + 1)[:-1, None])
    parts.append(path[-1:])
    return np.vstack(parts)


# ------------------------------------------------------------------------------ IK
def pose_matrix(xyz: Any, quat_wxyz: Any) -> Array:
    """4x4 from a position and a (w, x, y, z) quaternion."""
    return pose(quat_matrix(*(float(v) for v in quat_wxyz)), xyz)


def _rotation_angle(a: Array, b: Array) -> float:
    """The angle (rad) of the rotation between two rotation matrices."""
    return math.acos(max(-1.0, min(1.0, (float(np.trace(a.T @ b)) - 1.0) / 2.0)))


@dataclass(frozen=True)
class IkCheck:
    verified: bool
    position_error_m: float | None
    orientation_error_rad: float | None
    within_limits: bool | None


def check_ik(kin: Kinematics, problem: dict[str, Any], result: dict[str, Any],
             tolerance: dict[str, float], tip: str = "tool0") -> IkCheck:
    """Does the answer reach the target within the tolerance and the joint limits?"""
    q = result.get("q") if result.get("success") else None
    if q is None:
        return IkCheck(False, None, None, None)
    q = np.asarray(q, float)
    kin.update(q)
    reached = kin.frame(tip)
    target = pose_matrix(problem["xyz"], problem["quat_wxyz"])
    dp = float(np.linalg.norm(reached[:3, 3] - target[:3, 3]))
    do = _rotation_angle(reached[:3, :3], target[:3, :3])
    inside = kin.inside(q)
    ok = dp <= tolerance["position_m"] and do <= tolerance["orientation_rad"] and inside
    return IkCheck(ok, dp, do, inside)


# ------------------------------------------------------------------------------ paths
@dataclass(frozen=True)
class PathCheck:
    verified: bool
    ends_match: bool | None
    ends_off_by_turns: bool | None
    """The ends differ from start/goal by whole turns (2 pi) only: a different configuration
    for a joint whose range exceeds 2 pi (mplib wraps revolute joints)."""
    within_limits: bool | None
    collision_free: bool | None
    length: float | None
    waypoints: int | None


def check_path(judge: Judge, problem: dict[str, Any], result: dict[str, Any]) -> PathCheck:
    """Start and goal, joint limits, dense brute-force collision check of a returned path."""
    path = result.get("path") if result.get("success") else None
    if not path:
        return PathCheck(False, None, None, None, None, None, None)
    p = np.asarray(path, float)
    ends = bool(np.allclose(p[0], problem["start"], atol=1e-6)
                and np.allclose(p[-1], problem["goal"], atol=1e-6))
    off = np.concatenate([p[0] - problem["start"], p[-1] - problem["goal"]])
    turns = bool(not ends and np.allclose(off, 2 * np.pi * np.round(off / (2 * np.pi)),
                                          atol=1e-6))
    inside = judge.kin.inside(p)
    free = judge.path_free(p)
    length = float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))
    return PathCheck(ends and inside and free, ends, turns, inside, free, length, len(p))


# ------------------------------------------------------------------------------ trajectories
@dataclass(frozen=True)
class TrajectoryCheck:
    verified: bool
    ends_match: bool
    max_velocity_ratio: float
    max_acceleration_ratio: float
    collision_free: bool


def check_trajectory(judge: Judge, waypoints: Array, t: Array, q: Array, vmax: Array,
                     amax: Array) -> TrajectoryCheck:
    """End points, finite-difference velocity and acceleration against the limits, and the
    samples (densified) against the scene."""
    ends = bool(np.allclose(q[0], waypoints[0], atol=1e-4)
                and np.allclose(q[-1], waypoints[-1], atol=1e-4))
    dt = np.diff(t)
    keep = dt > 1e-9
    v = np.diff(q, axis=0)[keep] / dt[keep, None]
    vr = float(np.max(np.abs(v) / vmax)) if len(v) else 0.0
    ar = 0.0
    if len(v) > 2:
        mid = (dt[keep][1:] + dt[keep][:-1]) / 2
        a = np.diff(v, axis=0) / mid[:, None]
        ar = float(np.max(np.abs(a) / amax))
    free = judge.path_free(q)
    ok = ends and vr <= VELOCITY_SLACK and ar <= ACCELERATION_SLACK and free
    return TrajectoryCheck(ok, ends, vr, ar, free)
