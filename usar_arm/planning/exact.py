"""The exact collision checks, with python-fcl: the one module that imports ``fcl``.

:class:`ExactJudge` holds the FCL objects of an arm's link cylinders and of a scene's obstacles,
and answers what the compiled verdicts (:mod:`.verdicts`) leave undecided: contact of a pair,
penetration depth, distance. Poses are 4x4 (or 3x4) in base_link; metres.
"""

from __future__ import annotations

import copy

import fcl
import numpy as np
from numpy.typing import NDArray

from usar_arm.core.shapes import Shape
from usar_arm.core.spatial import Array
from usar_arm.planning import bounds
from usar_arm.planning.bounds import IndexArray
from usar_arm.planning.scene import (
    Box,
    Capsule,
    CylinderShape,
    Mesh,
    Scene,
    SceneObject,
    Sphere,
)


def _fcl_transform(t: Array) -> fcl.Transform:
    return fcl.Transform(np.ascontiguousarray(t[:3, :3]), np.ascontiguousarray(t[:3, 3]))


def shape_geometry(shape: object) -> fcl.CollisionGeometry:
    """The python-fcl geometry of a shape (box, cylinder, sphere, capsule or triangle mesh), in
    the shape's own frame (m)."""
    if isinstance(shape, Box):
        return fcl.Box(*shape.size)
    if isinstance(shape, CylinderShape):
        return fcl.Cylinder(shape.radius, shape.length)
    if isinstance(shape, Sphere):
        return fcl.Sphere(shape.radius)
    if isinstance(shape, Capsule):
        return fcl.Capsule(shape.radius, shape.length)
    if isinstance(shape, Mesh):
        model = fcl.BVHModel()
        model.beginModel(len(shape.vertices), len(shape.faces))
        model.addSubModel(np.asarray(shape.vertices, dtype=float),
                          np.asarray(shape.faces, dtype=np.int32))
        model.endModel()
        return model
    raise TypeError(f"unsupported shape {shape!r}")


def _aabb(o: SceneObject) -> Array:
    """World AABB (2 x 3: min, max; m) of a static scene object."""
    shape, pose = o.shape, o.pose
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


def _gap(a: Array, b: Array) -> float:
    """Distance (m) between two AABBs (2 x 3), 0 when they overlap: a lower bound of the
    distance of what they enclose."""
    return float(np.linalg.norm(np.maximum(0, np.maximum(a[0] - b[1], b[0] - a[1]))))


class ExactJudge:
    """python-fcl objects of the link cylinders (radius, half-length (m) per link) and of a
    scene's obstacles."""

    def __init__(self, shapes: list[Shape], to_shape: list[Array | None], radius: Array,
                 half: Array, scene: Scene):
        self.radius, self.half = radius, half
        self.shapes, self.to_shape = shapes, to_shape
        self._geometry = [shape_geometry(s) for s in shapes]  # (shared by in_scene's copies)
        self._robot = [fcl.CollisionObject(g, fcl.Transform()) for g in self._geometry]
        self._request = fcl.CollisionRequest()
        self._contact_request = fcl.CollisionRequest(num_max_contacts=1, enable_contact=True)
        self._init_scene(scene)

    def in_scene(self, scene: Scene) -> ExactJudge:
        """The same bodies with another scene's obstacles: objects of their own (each world
        places its bodies), on the same geometry (a mesh's BVH is built once)."""
        other = copy.copy(self)
        other._robot = [fcl.CollisionObject(g, fcl.Transform()) for g in self._geometry]
        other._init_scene(scene)
        return other

    def _init_scene(self, scene: Scene) -> None:
        self._static = [fcl.CollisionObject(shape_geometry(o.shape), _fcl_transform(o.pose))
                        for o in scene.objects]
        self._static_box = np.array([_aabb(o) for o in scene.objects]).reshape(-1, 2, 3)

    def _placed(self, i: int, poses: Array, placed: dict[int, fcl.CollisionObject]
                ) -> fcl.CollisionObject:
        """Robot body ``i`` moved to ``poses[i]`` (its bounding cylinder's pose; once per
        configuration)."""
        o = placed.get(i)
        if o is None:
            o = self._robot[i]
            pose, t = poses[i], self.to_shape[i]
            if t is None:
                o.setRotation(pose[:3, :3])
                o.setTranslation(pose[:3, 3])
            else:  # (one 3 x 4 product; the setters copy the views they are given)
                m = pose[:3, :3] @ t[:3]
                m[:, 3] += pose[:3, 3]
                o.setRotation(m[:, :3])
                o.setTranslation(m[:, 3])
            placed[i] = o
        return o

    def _collide(self, a: fcl.CollisionObject, b: fcl.CollisionObject) -> bool:
        return bool(fcl.collide(a, b, self._request, fcl.CollisionResult()) > 0)

    def undecided(self, poses: Array, verdicts: NDArray[np.int8], rr: IndexArray,
                  rs: IndexArray) -> list[int]:
        """The checked pairs (indices: robot-robot ``rr`` first, then robot-scene ``rs``) in
        contact, given the compiled verdicts: proven contacts as they are, FCL's answer on the
        undecided ones (link poses (L, 3, 4))."""
        found = [int(p) for p in np.flatnonzero(verdicts == bounds.CONTACT)]
        placed: dict[int, fcl.CollisionObject] = {}
        for p in np.flatnonzero(verdicts == bounds.UNDECIDED).tolist():
            if self._pair_collides(p, poses, rr, rs, placed):
                found.append(p)
        return found

    def any_contact(self, poses: Array, verdicts: NDArray[np.int8], rr: IndexArray,
                    rs: IndexArray) -> bool:
        """Whether a checked pair is in contact, given the compiled verdicts: a proven contact,
        else FCL's answer on the undecided pairs, stopping at the first in contact (what
        :meth:`undecided` would find, without naming the pairs: the path of every collision
        query of a plan)."""
        placed: dict[int, fcl.CollisionObject] = {}
        for p in np.flatnonzero(verdicts).tolist():  # (CLEAR is 0)
            if verdicts[p] == bounds.CONTACT or self._pair_collides(p, poses, rr, rs, placed):
                return True
        return False

    def _pair_collides(self, p: int, poses: Array, rr: IndexArray, rs: IndexArray,
                       placed: dict[int, fcl.CollisionObject]) -> bool:
        """FCL's answer on checked pair ``p`` (robot-robot pairs first, then robot-scene)."""
        n_rr = len(rr)
        if p < n_rr:
            i, j = rr[p]
            other = self._placed(j, poses, placed)
        else:
            i, k = rs[p - n_rr]
            other = self._static[k]
        return self._collide(self._placed(i, poses, placed), other)

    def every_pair(self, world: Array, checked: list[tuple[bool, int, int]]) -> list[int]:
        """Indices into ``checked`` ((scene?, link, link or obstacle) triples) of the pairs FCL
        finds in contact, testing each directly (link poses ``world`` (L, 4, 4))."""
        placed: dict[int, fcl.CollisionObject] = {}
        return [n for n, (static, i, j) in enumerate(checked)
                if self._collide(self._placed(i, world, placed),
                                 self._static[j] if static else self._placed(j, world, placed))]

    def depth(self, world: Array, a: tuple[bool, int], b: tuple[bool, int]) -> float:
        """Penetration depth (m; 0 when FCL reports none) of two bodies, each (scene?, index)."""
        placed: dict[int, fcl.CollisionObject] = {}
        oa, ob = (self._static[k] if static else self._placed(k, world, placed)
                  for static, k in (a, b))
        res = fcl.CollisionResult()
        fcl.collide(oa, ob, self._contact_request, res)
        return float(max((c.penetration_depth for c in res.contacts), default=0.0))

    def distance(self, world: Array, rr: IndexArray, rs: IndexArray) -> float:
        """Minimum clearance (m) over the checked pairs (0 or less in contact), link poses
        ``world`` (L, 4, 4). Pairs are visited in order of their AABB gap (a lower bound of
        their distance) and the search stops when the next gap exceeds the best distance."""
        z = world[:, :3, 2]
        half = (np.abs(z) * self.half[:, None]
                + self.radius[:, None] * np.sqrt(np.clip(1.0 - z * z, 0.0, 1.0)))
        c = world[:, :3, 3]
        box = np.stack([c - half, c + half], axis=1)
        jobs = [(_gap(box[i], box[j]), int(i), int(j), False) for i, j in rr]
        jobs += [(_gap(box[i], self._static_box[k]), int(i), int(k), True) for i, k in rs]
        best = float("inf")
        request = fcl.DistanceRequest()
        placed: dict[int, fcl.CollisionObject] = {}
        for gap, i, j, static in sorted(jobs):
            if gap > best:
                break
            other = self._static[j] if static else self._placed(j, world, placed)
            d = fcl.distance(self._placed(i, world, placed), other, request, fcl.DistanceResult())
            best = min(best, float(d))
        return float(best)
