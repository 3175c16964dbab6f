"""The correctness checks every solver's answers go through, ours as much as the peers'.

* IK: forward kinematics (Pinocchio, the shared URDF) of the answer against the target pose, and
  the joint limits.
* Collision: :class:`Judge`, a brute-force python-fcl check of every pair the SRDF and the scene
  leave enabled. It shares nothing with ``usar_arm.planning.collision`` (nor its compiled
  broadphase) but the URDF's link cylinders and the scene's shapes: its own FCL primitives
  built here, its own FCL objects, no broadphase (an exact bounding-sphere
  test only skips pairs that cannot touch), FCL's default request.
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
from scipy.spatial import cKDTree

from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, Sphere
from usar_arm.robot import Robot
from usar_arm.spatial import Array, matrix_from_quat, rotation_distance

PATH_STEP = 0.005
"""rad or m: largest joint change between two configurations the judge checks on a path (half
our planner's edge resolution, so the judge also looks between our planner's checks)."""
KD_TREE_FROM = 64
"""Scenes with more obstacles than this look up the ones smaller than a metre in a KD-tree."""
BLOCK = 128
"""Configurations the judge's vectorised prefilter handles at once (memory: 1,000 boxes)."""
LIMIT_SLACK = 1e-6
"""rad or m beyond a joint limit still accepted (TRAC-IK keeps limits as float32)."""
VELOCITY_SLACK = 1.02
ACCELERATION_SLACK = 1.10
"""Allowed ratio of finite-difference velocity / acceleration to the limit (100 Hz samples)."""


def _tf(t: Array) -> fcl.Transform:
    return fcl.Transform(np.ascontiguousarray(t[:3, :3]), np.ascontiguousarray(t[:3, 3]))


def _geometry(shape: object) -> fcl.CollisionGeometry:
    """The judge's own python-fcl primitive of a scene shape, in the shape's frame (m)."""
    if isinstance(shape, Box):
        return fcl.Box(*(float(x) for x in shape.size))
    if isinstance(shape, CylinderShape):
        return fcl.Cylinder(float(shape.radius), float(shape.length))
    if isinstance(shape, Sphere):
        return fcl.Sphere(float(shape.radius))
    if isinstance(shape, Mesh):
        mesh = fcl.BVHModel()
        mesh.beginModel(len(shape.vertices), len(shape.faces))
        mesh.addSubModel(np.asarray(shape.vertices, float), np.asarray(shape.faces, np.int32))
        mesh.endModel()
        return mesh
    raise TypeError(f"the judge has no geometry for {shape!r}")


class Judge:
    """Brute-force collision check of one robot in one scene (python-fcl).

    Args:
        robot: the shared description (URDF cylinders, SRDF disabled pairs).
        scene: obstacles; an object's ``allow`` list exempts those links from it.
    """

    def __init__(self, robot: Robot, scene: Scene):
        self.robot = robot
        links = [lk for lk in robot.chain.links if lk.geometry is not None]
        self.links = [lk.name for lk in links]
        self.local = np.array([lk.geometry.origin.matrix() for lk in links])  # type: ignore
        cyl = [lk.geometry for lk in links]
        self._cylinders = cyl
        self.robot_objects = [fcl.CollisionObject(fcl.Cylinder(c.radius, c.length),  # type: ignore
                                                  fcl.Transform()) for c in cyl]
        self.link_radius = np.array([math.hypot(c.radius, c.length / 2) for c in cyl])  # type: ignore
        self.objects = [fcl.CollisionObject(_geometry(o.shape), _tf(o.pose))
                        for o in scene.objects]
        self.object_centre = np.array([o.pose[:3, 3] for o in scene.objects]).reshape(-1, 3)
        self.object_radius = np.array([o.bounding_radius() for o in scene.objects])
        # boxes: centre, axes and half sizes for an exact sphere-box distance
        self.is_box = np.array([isinstance(o.shape, Box) for o in scene.objects], dtype=bool)
        self.box_rot = np.array([o.pose[:3, :3] for o in scene.objects]).reshape(-1, 3, 3)
        self.box_half = np.array([np.asarray(o.shape.size) / 2 if isinstance(o.shape, Box)
                                  else np.zeros(3) for o in scene.objects]).reshape(-1, 3)
        disabled = {tuple(sorted(p)) for p in robot.disabled}
        n = len(self.links)
        self.rr = np.array([(i, j) for i, j in itertools.combinations(range(n), 2)
                            if tuple(sorted((self.links[i], self.links[j]))) not in disabled],
                           dtype=int).reshape(-1, 2)
        self.allowed = np.array([[self.links[i] not in o.allow for o in scene.objects]
                                 for i in range(n)], dtype=bool).reshape(n, -1)
        few = len(scene.objects) <= KD_TREE_FROM
        self.big = np.flatnonzero(few | (self.object_radius > 1.0))
        self.small = np.flatnonzero(~few & (self.object_radius <= 1.0))
        self.small_radius = float(self.object_radius[self.small].max()) if len(self.small) \
            else 0.0
        self.tree = cKDTree(self.object_centre[self.small]) if len(self.small) else None
        self.request = fcl.CollisionRequest()
        self.frames = [robot.kinematics.frame_id(name) for name in self.links]

    def capsules(self, qs: Array) -> tuple[Array, Array, Array]:
        """Every link cylinder at every configuration as a capsule: axis ends a, b (M, 3) and
        radius (M,) (a capsule contains its cylinder)."""
        poses = self._poses(np.atleast_2d(np.asarray(qs, float)))
        half = np.array([c.length / 2 for c in self._cylinders])
        axis = poses[..., :3, 2] * half[:, None]
        centre = poses[..., :3, 3]
        radius = np.broadcast_to([c.radius for c in self._cylinders], centre.shape[:2])
        return ((centre - axis).reshape(-1, 3), (centre + axis).reshape(-1, 3),
                np.asarray(radius).reshape(-1))

    def _poses(self, qs: Array) -> Array:
        """World poses (N, L, 4, 4) of the link cylinders."""
        kin = self.robot.kinematics
        out = np.empty((len(qs), len(self.links), 4, 4))
        for n, q in enumerate(qs):
            kin.update(q)
            for k, fid in enumerate(self.frames):
                out[n, k] = kin.data.oMf[fid].homogeneous
        return out @ self.local

    def _near_objects(self, centre: Array) -> list[Array]:
        """Per configuration, the (link, object) pairs whose link bounding sphere reaches the
        object: the exact sphere-box distance for boxes, bounding spheres otherwise. In large
        scenes, objects within a metre's radius are found through a KD-tree of their centres;
        the others (floors, table tops; every object of a small scene) are tested directly.
        Conservative: a pair left out cannot touch."""
        n_cfg, n_links = centre.shape[:2]
        found: list[list[Array]] = [[] for _ in range(n_cfg)]
        if len(self.big):
            c = centre[:, :, None, :] - self.object_centre[self.big]        # (N, L, B, 3)
            near = self._reach(c, np.broadcast_to(self.big, c.shape[:3]),
                               self.link_radius[None, :, None])
            for n, i, b in zip(*np.nonzero(near & self.allowed[:, self.big]), strict=True):
                found[n].append((i, self.big[b]))
        if self.tree is not None:
            radii = np.broadcast_to(self.link_radius + self.small_radius, (n_cfg, n_links))
            hits = self.tree.query_ball_point(centre.reshape(-1, 3), radii.reshape(-1))
            for flat, ks in enumerate(hits):
                if not ks:
                    continue
                n, i = divmod(flat, n_links)
                ks = self.small[np.asarray(ks, dtype=int)]
                ks = ks[self.allowed[i, ks]]
                d = centre[n, i] - self.object_centre[ks]
                keep = self._reach(d, ks, self.link_radius[i])
                found[n] += [(i, k) for k in ks[keep]]
        return [np.array(f, dtype=int).reshape(-1, 2) for f in found]

    def _reach(self, d: Array, objects: Array, radius: Array | float) -> Array:
        """Whether spheres of ``radius`` at offsets ``d`` (..., 3) from the centres of
        ``objects`` (...) reach them (exact for boxes, bounding spheres otherwise)."""
        rot, half = self.box_rot[objects], self.box_half[objects]
        local = np.einsum("...ji,...j->...i", rot, d)                    # R^T d
        box_gap = np.linalg.norm(local - np.clip(local, -half, half), axis=-1)
        sphere_gap = np.linalg.norm(d, axis=-1) - self.object_radius[objects]
        gap = np.where(self.is_box[objects], box_gap, sphere_gap)
        return gap <= radius + 1e-9

    def colliding(self, qs: Array, stop_at_first: bool = False) -> Array:
        """True where a configuration (N, n) has a contact in any enabled pair."""
        qs = np.atleast_2d(np.asarray(qs, float))
        if len(qs) > BLOCK:
            out = np.zeros(len(qs), dtype=bool)
            for lo in range(0, len(qs), BLOCK):
                out[lo:lo + BLOCK] = self.colliding(qs[lo:lo + BLOCK], stop_at_first)
                if stop_at_first and out[lo:lo + BLOCK].any():
                    break
            return out
        poses = self._poses(qs)
        centre = poses[:, :, :3, 3]
        rr = self.rr
        near_rr = (np.linalg.norm(centre[:, rr[:, 0]] - centre[:, rr[:, 1]], axis=2)
                   <= self.link_radius[rr[:, 0]] + self.link_radius[rr[:, 1]] + 1e-9)
        near_rs = self._near_objects(centre)
        out = np.zeros(len(qs), dtype=bool)
        for n in range(len(qs)):
            pairs_rr, pairs_rs = rr[near_rr[n]], near_rs[n]
            for i in set(pairs_rr.ravel()) | set(pairs_rs[:, 0]):
                self.robot_objects[i].setTransform(_tf(poses[n, i]))
            hit = any(fcl.collide(self.robot_objects[i], self.robot_objects[j], self.request,
                                  fcl.CollisionResult()) > 0 for i, j in pairs_rr)
            hit = hit or any(fcl.collide(self.robot_objects[i], self.objects[k], self.request,
                                         fcl.CollisionResult()) > 0 for i, k in pairs_rs)
            out[n] = hit
            if hit and stop_at_first:
                break
        return out

    def path_free(self, path: Array, step: float = PATH_STEP) -> bool:
        """Every configuration along the polyline ``path`` (k, n), at most ``step`` apart per
        joint, is free."""
        return not self.colliding(densify(np.asarray(path, float), step),
                                  stop_at_first=True).any()


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
    t = np.eye(4)
    t[:3, :3] = matrix_from_quat(quat_wxyz)
    t[:3, 3] = xyz
    return t


@dataclass(frozen=True)
class IkCheck:
    verified: bool
    position_error_m: float | None
    orientation_error_rad: float | None
    within_limits: bool | None


def check_ik(robot: Robot, problem: dict[str, Any], result: dict[str, Any],
             tolerance: dict[str, float], tip: str = "tool0") -> IkCheck:
    """Does the answer reach the target within the tolerance and the joint limits?"""
    q = result.get("q") if result.get("success") else None
    if q is None:
        return IkCheck(False, None, None, None)
    q = np.asarray(q, float)
    pose = robot.kinematics.frame_pose(q, tip)
    target = pose_matrix(problem["xyz"], problem["quat_wxyz"])
    dp = float(np.linalg.norm(pose[:3, 3] - target[:3, 3]))
    do = float(rotation_distance(pose[:3, :3], target[:3, :3]))
    lo, hi = robot.chain.lower(), robot.chain.upper()
    inside = bool(np.all(q >= lo - LIMIT_SLACK) and np.all(q <= hi + LIMIT_SLACK))
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


def check_path(robot: Robot, judge: Judge, problem: dict[str, Any], result: dict[str, Any]
               ) -> PathCheck:
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
    lo, hi = robot.chain.lower(), robot.chain.upper()
    inside = bool(np.all(p >= lo - LIMIT_SLACK) and np.all(p <= hi + LIMIT_SLACK))
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
