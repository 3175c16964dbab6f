"""Collision checking of the arm against itself and a scene, with python-fcl.

The robot's links are the URDF's cylinders (optionally padded); pairs the SRDF disables are never
checked. A broadphase (FCL's dynamic AABB trees) culls pairs whose boxes do not overlap before
the exact narrowphase. :meth:`CollisionWorld.contacts_brute_force` checks every pair directly and
is the reference the broadphase is tested against.

This is the only module that imports ``fcl``.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable
from dataclasses import dataclass

import fcl
import numpy as np
from numpy.typing import NDArray

from usar_arm.core.model import Cylinder, KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning import bounds
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.planning.poe import PoeModel
from usar_arm.planning.scene import EMPTY, Box, CylinderShape, Mesh, Scene, Sphere

Pair = tuple[str, str]


def pair(a: str, b: str) -> Pair:
    """A link/object pair in canonical (sorted) order."""
    return (a, b) if a <= b else (b, a)


def _fcl_transform(t: Array) -> fcl.Transform:
    return fcl.Transform(np.ascontiguousarray(t[:3, :3]), np.ascontiguousarray(t[:3, 3]))


def shape_geometry(shape: object) -> fcl.CollisionGeometry:
    """The python-fcl geometry of a scene shape (box, cylinder, sphere or triangle mesh), in
    the shape's own frame (m)."""
    if isinstance(shape, Box):
        return fcl.Box(*shape.size)
    if isinstance(shape, CylinderShape):
        return fcl.Cylinder(shape.radius, shape.length)
    if isinstance(shape, Sphere):
        return fcl.Sphere(shape.radius)
    if isinstance(shape, Mesh):
        model = fcl.BVHModel()
        model.beginModel(len(shape.vertices), len(shape.faces))
        model.addSubModel(np.asarray(shape.vertices, dtype=float),
                          np.asarray(shape.faces, dtype=np.int32))
        model.endModel()
        return model
    raise TypeError(f"unsupported shape {shape!r}")


@dataclass(frozen=True)
class Contact:
    """Two bodies in contact and how deep (m; 0 when FCL reports no depth)."""

    a: str
    b: str
    depth: float


class CollisionWorld:
    """The arm (cylinders from a chain) and a scene, checked with python-fcl.

    Broadphase: a compiled kernel (:mod:`.bounds`) computes every link's pose for a batch of
    configurations and clears the checked pairs that provably cannot touch (enclosing capsules,
    separating axes of the exact cylinder against boxes); only the pairs it cannot clear reach
    FCL's exact narrowphase, so only FCL ever reports a contact.

    Args:
        chain: the robot description (link cylinders).
        kinematics: its Pinocchio model (link poses).
        disabled: link pairs never checked (the SRDF's disable_collisions).
        scene: obstacles in base_link (default: none).
        padding: safety margin (m) added to every robot cylinder's radius and half-length.
    """

    def __init__(self, chain: KinematicChain, kinematics: KinematicModel,
                 disabled: Iterable[Pair] = (), scene: Scene = EMPTY, padding: float = 0.0):
        self.chain = chain
        self.kinematics = kinematics
        self.scene = scene
        self.padding = float(padding)
        links = [lk for lk in chain.links if lk.geometry is not None]
        self._links = [lk.name for lk in links]
        self._frame_ids = [kinematics.frame_id(n) for n in self._links]
        cyls: list[Cylinder] = [lk.geometry for lk in links if lk.geometry is not None]
        self._local = np.array([c.origin.matrix() for c in cyls]).reshape(-1, 4, 4)
        self._radius = np.array([c.radius + self.padding for c in cyls])
        self._half = np.array([c.length / 2 + self.padding for c in cyls])
        self._robot = [fcl.CollisionObject(fcl.Cylinder(r, 2 * h), fcl.Transform())
                       for r, h in zip(self._radius, self._half, strict=True)]
        self._poses = np.zeros((len(self._links), 4, 4))
        self._init_robot_bounds(chain, links)
        self._init_scene(scene)
        self._request = fcl.CollisionRequest()
        self._contact_request = fcl.CollisionRequest(num_max_contacts=1, enable_contact=True)
        self._levers: Array | None = None
        self._link_levers: Array | None = None
        self.set_disabled(disabled)

    def in_scene(self, scene: Scene) -> CollisionWorld:
        """The same arm (geometry, disabled pairs, padding) in another scene: only the scene's
        part is built, so a study that moves the scene around the arm (base placement) pays
        for the obstacles alone."""
        other = copy.copy(self)
        other._robot = [fcl.CollisionObject(fcl.Cylinder(r, 2 * h), fcl.Transform())
                        for r, h in zip(self._radius, self._half, strict=True)]
        other._poses = np.zeros_like(self._poses)
        other._init_scene(scene)
        other.set_disabled(self.disabled)
        return other

    def _init_scene(self, scene: Scene) -> None:
        """The scene's FCL objects, boxes and compiled arrays."""
        self.scene = scene
        self._static = [fcl.CollisionObject(shape_geometry(o.shape), _fcl_transform(o.pose))
                        for o in scene.objects]
        self._static_box = np.array([self._aabb(o) for o in scene.objects]).reshape(-1, 2, 3)
        self._names = self._links + [o.name for o in scene.objects]
        self._init_scene_bounds(scene)

    def _init_robot_bounds(self, chain: KinematicChain, links: list) -> None:
        """Plain arrays for the compiled broadphase: the chain as twists at zero and each link
        cylinder's pose at zero."""
        poe = PoeModel(chain)
        zero = chain.link_poses(np.zeros(chain.dof))
        self._axes = np.ascontiguousarray(poe.axes, dtype=float).reshape(-1, 3)
        self._points = np.ascontiguousarray(poe.points, dtype=float).reshape(-1, 3)
        self._revolute = np.ascontiguousarray(poe.revolute, dtype=np.int64).reshape(-1)
        self._moved_by = np.array([poe.joints_moving(lk.name) for lk in links], dtype=np.int64)
        self._zero = np.array([zero[lk.name] @ local for lk, local in
                               zip(links, self._local, strict=True)]).reshape(-1, 4, 4)

    def _init_scene_bounds(self, scene: Scene) -> None:
        """The obstacles as boxes, spheres, capsules and mesh hulls for the broadphase."""
        kinds, poses, sizes = [], [], []
        for o in scene.objects:
            shape, pose = o.shape, np.asarray(o.pose, float)
            size = np.zeros(3)
            if isinstance(shape, Box):
                kind, size[:] = bounds.BOX, np.asarray(shape.size, float) / 2
            elif isinstance(shape, Sphere):
                kind, size[0] = bounds.SPHERE, shape.radius
            elif isinstance(shape, CylinderShape):
                kind, size[:2] = bounds.CAPSULE, (shape.radius, shape.length / 2)
            elif isinstance(shape, Mesh):  # the box that bounds the mesh in its own frame
                v = np.asarray(shape.vertices, float)
                lo, hi = v.min(axis=0), v.max(axis=0)
                centre = np.eye(4)
                centre[:3, 3] = (lo + hi) / 2
                kind, size[:], pose = bounds.HULL, (hi - lo) / 2, pose @ centre
            else:
                raise TypeError(f"unsupported shape {shape!r}")
            kinds.append(kind)
            poses.append(pose[:3])
            sizes.append(size)
        self._kind = np.array(kinds, dtype=np.int64)
        self._opose = np.array(poses, dtype=float).reshape(-1, 3, 4)
        self._osize = np.array(sizes, dtype=float).reshape(-1, 3)

    def bounded_poses(self, qs: Array) -> tuple[Array, NDArray[np.int8]]:
        """World poses (N, L, 3, 4) of the link cylinders at configurations ``qs`` (N, n), and
        (N, P + Q) verdicts of the compiled tests on the robot-robot then robot-scene pairs
        (order of ``_rr``/``_rs``): :data:`~.bounds.CLEAR`, :data:`~.bounds.CONTACT` or
        :data:`~.bounds.UNDECIDED` (for FCL)."""
        qs = np.ascontiguousarray(np.atleast_2d(qs), dtype=float)
        return bounds.check(qs, *self._packed, bounds.EPS, bounds.MARGIN)

    @staticmethod
    def _aabb(obj: object) -> Array:
        """World AABB (2 x 3: min, max) of a static scene object."""
        o = obj  # SceneObject
        shape, pose = o.shape, o.pose  # type: ignore[attr-defined]
        if isinstance(shape, Mesh):
            pts = np.asarray(shape.vertices, dtype=float) @ pose[:3, :3].T + pose[:3, 3]
            return np.array([pts.min(axis=0), pts.max(axis=0)])
        if isinstance(shape, Box):
            half = np.abs(pose[:3, :3]) @ (np.asarray(shape.size) / 2)
        elif isinstance(shape, CylinderShape):
            z = pose[:3, 2]
            half = np.abs(z) * shape.length / 2 + shape.radius * np.sqrt(np.clip(1 - z * z, 0, 1))
        else:
            half = np.full(3, shape.radius)  # type: ignore[union-attr]
        return np.array([pose[:3, 3] - half, pose[:3, 3] + half])

    # ------------------------------------------------------------------ state
    def set_disabled(self, pairs: Iterable[Pair]) -> None:
        """Replace the set of robot-robot pairs that are never checked."""
        self.disabled = {pair(a, b) for a, b in pairs}
        allowed = {pair(link, o.name) for o in self.scene.objects for link in o.allow}
        self._skip = self.disabled | allowed
        n = len(self._links)
        rr = [(i, j) for i in range(n) for j in range(i + 1, n)
              if pair(self._links[i], self._links[j]) not in self._skip]
        rs = [(i, k) for i in range(n) for k, o in enumerate(self.scene.objects)
              if pair(self._links[i], o.name) not in self._skip]
        self._rr = np.array(rr, dtype=np.int64).reshape(-1, 2)
        self._rs = np.array(rs, dtype=np.int64).reshape(-1, 2)
        self._packed = bounds.pack(self._axes, self._points, self._revolute, self._zero,
                                   self._radius, self._half, self._moved_by, self._rr, self._rs,
                                   self._kind, self._opose, self._osize)

    def lever_arms(self) -> Array:
        """Per actuated joint (configuration order), a bound on how far any point of the robot's
        collision geometry moves per unit of that joint (m/rad; 1 for a prismatic joint).

        For a revolute joint: the largest distance from the joint's origin to a point of a
        cylinder downstream of it, bounded over every configuration by the lengths of the joint
        offsets in between (plus the travel of prismatic joints among them) and the cylinder's
        extent. Along a joint-space segment no point moves farther than the sum over joints of
        lever arm times joint change (see :func:`~usar_arm.planning.ompl_adapter.
        edge_configurations`).
        """
        if self._levers is None:
            levers = np.ascontiguousarray(self.link_levers().max(axis=1))
            levers.setflags(write=False)
            self._levers = levers
        return self._levers

    def link_levers(self) -> Array:
        """:meth:`lever_arms` per link cylinder: (n, L), how far any point of cylinder k moves
        per unit of joint j (m/rad, or 1 for a prismatic joint; 0 where joint j does not move
        cylinder k)."""
        if self._link_levers is None:
            joints = self.chain.actuated_joints
            levers = np.zeros((len(joints), len(self._links)))
            by_link = {lk.name: lk for lk in self.chain.links}
            for k, (name, radius, half) in enumerate(zip(self._links, self._radius, self._half,
                                                         strict=True)):
                path = self.chain.path_to(name)
                for i, jt in enumerate(joints):
                    if jt not in path:
                        continue
                    if jt.type.value == "prismatic":
                        levers[i, k] = 1.0
                        continue
                    reach = 0.0
                    for step in path[path.index(jt) + 1:]:
                        reach += float(np.linalg.norm(step.origin.xyz))
                        if step.type.value == "prismatic" and step.limits is not None:
                            reach += max(abs(step.limits.lower), abs(step.limits.upper))
                    geom = by_link[name].geometry
                    assert geom is not None
                    reach += float(np.linalg.norm(geom.origin.xyz)) + float(np.hypot(radius,
                                                                                      half))
                    levers[i, k] = reach
            levers.setflags(write=False)
            self._link_levers = levers
        return self._link_levers

    @property
    def link_names(self) -> tuple[str, ...]:
        """Links that have collision geometry."""
        return tuple(self._links)

    def checked_pairs(self) -> list[Pair]:
        """Every robot-robot and robot-scene pair that is checked (not disabled or allowed)."""
        out = [pair(self._links[i], self._links[j]) for i, j in self._rr]
        out += [pair(self._links[i], self.scene.objects[k].name) for i, k in self._rs]
        return sorted(out)

    def set_configuration(self, q: Array) -> None:
        """Place the robot's cylinders at configuration ``q`` (rad/m)."""
        self.kinematics.update(q)
        oMf = self.kinematics.data.oMf
        for k, fid in enumerate(self._frame_ids):
            self._poses[k] = oMf[fid].homogeneous
        self._world = self._poses @ self._local

    def _robot_boxes(self) -> Array:
        """World AABBs (n x 2 x 3) of the robot cylinders at the current configuration."""
        w = self._world
        z = w[:, :3, 2]
        half = (np.abs(z) * self._half[:, None]
                + self._radius[:, None] * np.sqrt(np.clip(1.0 - z * z, 0.0, 1.0)))
        c = w[:, :3, 3]
        return np.stack([c - half, c + half], axis=1)

    def _place(self, i: int) -> fcl.CollisionObject:
        obj = self._robot[i]
        obj.setTransform(_fcl_transform(self._world[i]))
        return obj

    # ------------------------------------------------------------------ queries
    def in_collision(self, q: Array) -> bool:
        """True when any checked pair overlaps at ``q``."""
        q = np.asarray(q, dtype=float)
        quick = bounds.summary(q if q.flags.c_contiguous else np.ascontiguousarray(q),
                               *self._packed, bounds.EPS, bounds.MARGIN)
        if quick != bounds.UNDECIDED:
            return bool(quick == bounds.CONTACT)
        world, verdicts = self.bounded_poses(q)
        if not verdicts.any():
            return False
        return bool(self._exact(world[0], verdicts[0], stop_at_first=True))

    def contacts(self, q: Array) -> list[Pair]:
        """Every checked pair in contact at ``q``, sorted."""
        world, verdicts = self.bounded_poses(q)
        return sorted(self._exact(world[0], verdicts[0], stop_at_first=False))

    def _exact(self, poses: Array, verdicts: Array, stop_at_first: bool) -> list[Pair]:
        """The pairs in contact, given the compiled verdicts: proven contacts as they are, FCL's
        answer on the undecided ones (link poses (L, 3, 4))."""
        proven = np.flatnonzero(verdicts == bounds.CONTACT)
        if stop_at_first and len(proven):
            return [self._pair_name(int(proven[0]))]
        found = [self._pair_name(int(p)) for p in proven]
        placed: dict[int, fcl.CollisionObject] = {}
        request = self._request
        n_rr = len(self._rr)
        for p in np.flatnonzero(verdicts == bounds.UNDECIDED):
            if p < n_rr:
                i, j = self._rr[p]
                other = self._placed(j, poses, placed)
            else:
                i, k = self._rs[p - n_rr]
                other = self._static[k]
            if fcl.collide(self._placed(i, poses, placed), other, request,
                           fcl.CollisionResult()) > 0:
                found.append(self._pair_name(int(p)))
                if stop_at_first:
                    return found
        return found

    def _pair_name(self, p: int) -> Pair:
        """The names of checked pair ``p`` (robot-robot pairs first, then robot-scene)."""
        n_rr = len(self._rr)
        if p < n_rr:
            i, j = self._rr[p]
            return pair(self._links[i], self._links[j])
        i, k = self._rs[p - n_rr]
        return pair(self._links[i], self.scene.objects[k].name)

    def contacts_brute_force(self, q: Array) -> list[Pair]:
        """Every checked pair in contact at ``q``, testing each pair with FCL, no broadphase.

        The reference implementation :meth:`contacts` and :meth:`in_collision` are tested
        against.
        """
        self.set_configuration(q)
        objects = [self._place(i) for i in range(len(self._links))]
        found = []
        for i, a in enumerate(self._links):
            for j in range(i + 1, len(self._links)):
                p = pair(a, self._links[j])
                if p not in self._skip and fcl.collide(objects[i], objects[j], self._request,
                                                       fcl.CollisionResult()) > 0:
                    found.append(p)
            for k, obj in enumerate(self.scene.objects):
                p = pair(a, obj.name)
                if p not in self._skip and fcl.collide(objects[i], self._static[k], self._request,
                                                       fcl.CollisionResult()) > 0:
                    found.append(p)
        return sorted(found)

    def contact_details(self, q: Array) -> list[Contact]:
        """The pairs in contact at ``q`` with their penetration depth (m)."""
        self.set_configuration(q)
        index = {n: i for i, n in enumerate(self._links)}
        statics = {o.name: k for k, o in enumerate(self.scene.objects)}
        out = []
        for a, b in self.contacts(q):
            oa = self._place(index[a]) if a in index else self._static[statics[a]]
            ob = self._place(index[b]) if b in index else self._static[statics[b]]
            res = fcl.CollisionResult()
            fcl.collide(oa, ob, self._contact_request, res)
            depth = max((c.penetration_depth for c in res.contacts), default=0.0)
            out.append(Contact(a, b, float(depth)))
        return out

    def distance(self, q: Array) -> float:
        """Minimum clearance (m) over the checked pairs at ``q`` (0 or less in contact).

        Pairs are visited in order of their AABB gap (a lower bound of their distance) and the
        search stops when the next gap exceeds the best distance found.
        """
        self.set_configuration(q)
        box = self._robot_boxes()
        jobs: list[tuple[float, int, int, bool]] = []
        for i, j in self._rr:
            gap = float(np.linalg.norm(np.maximum(0, np.maximum(box[i, 0] - box[j, 1],
                                                                box[j, 0] - box[i, 1]))))
            jobs.append((gap, int(i), int(j), False))
        for i, k in self._rs:
            s = self._static_box[k]
            gap = float(np.linalg.norm(np.maximum(0, np.maximum(box[i, 0] - s[1],
                                                                s[0] - box[i, 1]))))
            jobs.append((gap, int(i), int(k), True))
        best = float("inf")
        request = fcl.DistanceRequest()
        for gap, i, j, static in sorted(jobs):
            if gap > best:
                break
            other = self._static[j] if static else self._place(j)
            d = fcl.distance(self._place(i), other, request, fcl.DistanceResult())
            best = min(best, float(d))
        return float(best)

    # ------------------------------------------------------------------ batches
    def in_collision_many(self, qs: Array) -> Array:
        """:meth:`in_collision` for N configurations (N, n) at once -> bool (N,).

        Forward kinematics of every link and the bounding-volume tests run compiled over the
        whole batch; FCL's narrowphase runs only for the pairs they could not clear, stopping
        at a configuration's first contact. The fast path for edges and trajectories.
        """
        world, verdicts = self.bounded_poses(qs)
        hit = (verdicts == bounds.CONTACT).any(axis=1)
        for n in np.flatnonzero(~hit & (verdicts == bounds.UNDECIDED).any(axis=1)):
            hit[n] = bool(self._exact(world[n], verdicts[n], stop_at_first=True))
        return hit

    def segment_free(self, a: Array, b: Array, steps: int) -> bool:
        """True when none of the ``steps + 1`` evenly spaced configurations from ``a`` to ``b``
        (both included) is in collision: the answer of checking every one of them.

        The compiled walk (:func:`.bounds.walk`) skips configurations that the clearance at
        an earlier one proves free (a continuous guarantee between them), stops at a proven
        contact, and leaves the undecided ones to FCL, in order.
        """
        if steps < 1:
            raise ValueError(f"a segment needs at least 1 step, got {steps}")
        hit, _, _, poses, verdicts = bounds.walk(
            np.ascontiguousarray(a, dtype=float), np.ascontiguousarray(b, dtype=float),
            int(steps), self.link_levers(), *self._packed, bounds.EPS, bounds.MARGIN)
        if hit >= 0:
            return False
        return not any(self._exact(p, v, stop_at_first=True)
                       for p, v in zip(poses, verdicts, strict=True))

    def contacts_many(self, qs: Array) -> list[list[Pair]]:
        """:meth:`contacts` for N configurations at once."""
        return [sorted(p) for p in self._many(qs, stop_at_first=False)]

    def _placed(self, i: int, poses: Array, placed: dict[int, fcl.CollisionObject]
                ) -> fcl.CollisionObject:
        """Robot cylinder ``i`` moved to ``poses[i]`` (once per configuration)."""
        o = placed.get(i)
        if o is None:
            o = self._robot[i]
            o.setTransform(_fcl_transform(poses[i]))
            placed[i] = o
        return o

    def _many(self, qs: Array, stop_at_first: bool) -> list[list[Pair]]:
        world, verdicts = self.bounded_poses(qs)
        found: list[list[Pair]] = [[] for _ in range(len(world))]
        for n in np.flatnonzero(verdicts.any(axis=1)):
            found[n] = self._exact(world[n], verdicts[n], stop_at_first)
        return found
