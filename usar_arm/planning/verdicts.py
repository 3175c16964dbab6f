"""The compiled collision verdicts of an arm in a scene: the plain arrays :mod:`.bounds` takes
(the chain as twists, link cylinders, obstacles as boxes, spheres, capsules and mesh hulls, the
checked pairs), and the batches it answers: CLEAR / CONTACT / UNDECIDED per checked pair, the
single-query summary, the walk along a joint-space segment, and the lever arms that make the
walk's skips safe. No python-fcl here (:mod:`.exact` decides the undecided). Metres, radians.
"""

from __future__ import annotations

import copy
import itertools
import threading
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning import bounds, bounds_walk
from usar_arm.planning.bounds import IndexArray
from usar_arm.planning.bounds_arrays import Cover, Packed
from usar_arm.planning.poe import PoeModel
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, Sphere


def _scene_arrays(scene: Scene) -> tuple[IndexArray, Array, Array]:
    """The obstacles as kinds (O,), poses (O, 3, 4) and sizes (O, 3) for the broadphase."""
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
    return (np.array(kinds, dtype=np.int64), np.array(poses, dtype=float).reshape(-1, 3, 4),
            np.array(sizes, dtype=float).reshape(-1, 3))


def link_groups(links: list[str], radius: Array, half: Array, local: Array
                ) -> tuple[IndexArray, IndexArray, Array]:
    """Per body: the index of its link (first appearance order), the body whose axis segment
    every body of that link lies along (-1 when the link has one body, or bodies that are not
    coaxial with its longest one and within its length), and the radius of the capsule around
    that segment holding them all (m). A learnt arm's link is its body cylinder and its core
    along one axis: one capsule, the core's segment with the body's radius."""
    names = list(dict.fromkeys(links))
    owner = np.array([names.index(name) for name in links], dtype=np.int64)
    group = np.full(len(links), -1, dtype=np.int64)
    group_radius = np.zeros(len(links))
    for k in range(len(names)):
        members = np.flatnonzero(owner == k)
        if len(members) < 2:
            continue
        rep = int(members[np.argmax(half[members])])
        axis, centre = local[rep][:3, 2], local[rep][:3, 3]
        coaxial = True
        for e in members:
            d = local[e][:3, 3] - centre
            along = float(d @ axis)
            off_axis = float(np.linalg.norm(d - along * axis))
            parallel = float(np.linalg.norm(np.cross(local[e][:3, 2], axis)))
            coaxial &= (parallel < 1e-9 and off_axis < 1e-9
                        and abs(along) + half[e] <= half[rep] + 1e-9)
        if coaxial:
            group[members] = rep
            group_radius[members] = float(radius[members].max()) + 1e-9
    return owner, group, group_radius


def _group_chains(group: IndexArray, rs: IndexArray) -> IndexArray:
    """Per body, the next body of its group (the group's body first, then the others in
    order; -1 after the last and for ungrouped bodies). The scene kernel clears a group's
    bodies together, so they must be checked against the same obstacles.

    Raises:
        ValueError: two bodies of one group with different checked obstacles."""
    chain = np.full(len(group), -1, dtype=np.int64)
    for rep in np.unique(group[group >= 0]):
        members = [int(rep), *[int(m) for m in np.flatnonzero(group == rep) if m != rep]]
        obstacles = {m: set(rs[rs[:, 0] == m, 1].tolist()) for m in members}
        if any(obstacles[m] != obstacles[members[0]] for m in members):
            raise ValueError(f"bodies {members} of one link are checked against different "
                             "obstacles; pairs must be disabled link by link")
        for a, b in itertools.pairwise(members):
            chain[a] = b
    return chain


def _plain(a: Array) -> Array:
    """``a`` as the kernels were compiled for: float64, C-contiguous, writeable. A read-only
    array (a frozen home configuration, a cached reading) is another type to numba: passing
    it compiled the kernel again at first use, seconds in a fresh install."""
    a = np.asarray(a)
    if a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable:
        return a
    return np.array(a, dtype=np.float64, order="C")


NO_PROOF = -1.0e6
"""The inner-ball radius (m) given to a body whose bounding cylinder is not its shape (a box,
a mesh): no overlap of such balls is ever below zero, so the verdicts never prove its contacts
(they clear its pairs; python-fcl decides the rest)."""


class CompiledVerdicts:
    """The compiled broadphase of collision bodies (each a cylinder: radius and half-length
    padded, m; pose in its link ``links[k]``'s frame ``local`` (L, 4, 4); ``exact[k]`` False
    when it only bounds the body's shape; ``covers[k]``: the balls around a mesh body's
    surface, groups and leaves of :class:`.ball_cover.BallCover`, and the balls inside it:
    :data:`.bounds_arrays.Cover`; ``solid[k]`` False when the body is not the cylinder itself
    but a sphere or capsule whose balls it shares: no rim proofs; default: every exact body is
    its cylinder) in a scene."""

    def __init__(self, chain: KinematicChain, links: list[str], radius: Array, half: Array,
                 local: Array, scene: Scene, exact: NDArray[np.bool_] | None = None,
                 covers: list[Cover | None] | None = None,
                 solid: NDArray[np.bool_] | None = None):
        poe = PoeModel(chain)
        zero = chain.link_poses(np.zeros(chain.dof))
        self.chain = chain
        self.names = list(links)
        self.radius, self.half = radius, half
        self._local = local
        self._exact = np.ones(len(links), bool) if exact is None else np.asarray(exact, bool)
        self._solid = self._exact & (np.ones(len(links), bool) if solid is None
                                     else np.asarray(solid, bool))
        self._covers = covers  # (per body: its balls' groups, leaves and inner balls, or None)
        self._axes = np.ascontiguousarray(poe.axes, dtype=float).reshape(-1, 3)
        self._points = np.ascontiguousarray(poe.points, dtype=float).reshape(-1, 3)
        self._revolute = np.ascontiguousarray(poe.revolute, dtype=np.int64).reshape(-1)
        self._moved_by = np.array([poe.joints_moving(name) for name in links], dtype=np.int64)
        self._zero = np.array([zero[name] @ m for name, m in
                               zip(links, local, strict=True)]).reshape(-1, 4, 4)
        self._link_levers: Array | None = None
        self._owner, self._group, self._group_radius = link_groups(self.names, radius, half,
                                                                   np.asarray(local, float))
        self._kind, self._opose, self._osize = _scene_arrays(scene)
        self.rr: IndexArray = np.zeros((0, 2), dtype=np.int64)
        self.rs: IndexArray = np.zeros((0, 2), dtype=np.int64)

    def in_scene(self, scene: Scene) -> CompiledVerdicts:
        """The same arm in another scene (call :meth:`check_pairs` next)."""
        other = copy.copy(self)
        other._kind, other._opose, other._osize = _scene_arrays(scene)
        return other

    def check_pairs(self, rr: IndexArray, rs: IndexArray) -> None:
        """Check the robot-robot pairs ``rr`` (P, 2: link, link) and robot-scene pairs ``rs``
        (Q, 2: link, obstacle), in that order."""
        self._scratch = threading.local()  # (per thread: summary's output arrays)
        rr = np.array(rr, dtype=np.int64).reshape(-1, 2)
        # the rows of one link pair next to each other, for the kernel's block test
        self.rr = rr[np.lexsort((self._owner[rr[:, 1]], self._owner[rr[:, 0]]))] if len(rr) \
            else rr
        self.rs = np.array(rs, dtype=np.int64).reshape(-1, 2)
        self._packed = bounds.pack(self._axes, self._points, self._revolute, self._zero,
                                   self.radius, self.half, self._moved_by, self.rr, self.rs,
                                   self._kind, self._opose, self._osize, self._covers)
        links = self._packed.links
        links[:, bounds.OWNER] = self._owner
        links[:, bounds.GROUP] = self._group
        links[:, bounds.GROUP_RADIUS] = self._group_radius
        links[:, bounds.NEXT] = _group_chains(self._group, self.rs)
        if not self._exact.all():
            links[~self._exact, bounds.RHO] = NO_PROOF
            links[~self._exact, bounds.REACH] = 0.0
        links[:, bounds.SOLID] = self._solid

    @property
    def packed(self) -> Packed:
        """The arrays the kernels take (:class:`.bounds_arrays.Packed`), as :meth:`check_pairs`
        prepared them: the kernels' own, not a copy (never write to them)."""
        return self._packed

    def check(self, qs: Array) -> tuple[Array, NDArray[np.int8], NDArray[np.int8]]:
        """World poses (N, L, 3, 4) of the link cylinders at configurations ``qs`` (N, n),
        (N, P + Q) verdicts on the checked pairs (:data:`~.bounds.CLEAR`,
        :data:`~.bounds.CONTACT` or :data:`~.bounds.UNDECIDED`) and one per configuration (N,)
        (CONTACT when a pair is proven in contact, else UNDECIDED when one is undecided)."""
        qs = _plain(np.atleast_2d(qs))
        return bounds.check(qs, self._packed, bounds.EPS, bounds.MARGIN)

    def summary(self, q: Array) -> tuple[int, Array, NDArray[np.int8]]:
        """One verdict for configuration ``q`` (CLEAR when every pair is, CONTACT when one is,
        else UNDECIDED), the link cylinder poses (L, 3, 4) and the pair verdicts (P + Q,): the
        calling thread's arrays, valid until its next call."""
        buffers = getattr(self._scratch, "buffers", None)
        if buffers is None:  # (allocated once per thread: a query that clears costs nothing)
            zero, pairs = self._packed.zero, self._packed.pairs
            buffers = (np.empty((zero.shape[0], 3, 4)), np.empty(pairs.shape[0], dtype=np.int8))
            self._scratch.buffers = buffers
        world, row = buffers
        verdict = bounds.summary(_plain(q), world, row, *self._packed, bounds.EPS,
                                 bounds.MARGIN)  # (positional: see bounds.summary)
        return int(verdict), world, row

    def segment_free(self, a: Array, b: Array, steps: int,
                     in_contact: Callable[[Array, NDArray[np.int8]], bool]) -> tuple[bool, int]:
        """:func:`.bounds_walk.segment_free` from ``a`` to ``b``: whether every one of the
        ``steps + 1`` configurations is free, ``in_contact(poses, verdicts)`` deciding those
        the bounding volumes leave undecided as they come (coarse to fine); and how many
        configurations the compiled walk evaluated."""
        return bounds_walk.segment_free(_plain(a), _plain(b), int(steps), self.link_levers(),
                                        self._packed, bounds.EPS, bounds.MARGIN, in_contact)

    def link_levers(self) -> Array:
        """Per actuated joint and link cylinder (n, L), how far any point of cylinder k moves
        per unit of joint j (m/rad, or 1 for a prismatic joint; 0 where joint j does not move
        cylinder k)."""
        if self._link_levers is None:
            joints = self.chain.actuated_joints
            levers = np.zeros((len(joints), len(self.names)))
            for k, name in enumerate(self.names):
                path = self.chain.path_to(name)
                for i, jt in enumerate(joints):
                    if jt in path:
                        levers[i, k] = self._reach(name, path, path.index(jt), k)
            levers.setflags(write=False)
            self._link_levers = levers
        return self._link_levers

    def _reach(self, name: str, path: list, at: int, k: int) -> float:
        """The lever arm of joint ``path[at]`` on cylinder ``k`` of link ``name``: the joint
        offsets downstream, the travel of prismatic joints among them, and the cylinder's
        extent (m; 1 for a prismatic joint)."""
        if path[at].type.value == "prismatic":
            return 1.0
        reach = 0.0
        for step in path[at + 1:]:
            reach += float(np.linalg.norm(step.origin.xyz))
            if step.type.value == "prismatic" and step.limits is not None:
                reach += max(abs(step.limits.lower), abs(step.limits.upper))
        return reach + float(np.linalg.norm(self._local[k][:3, 3])) + float(
            np.hypot(self.radius[k], self.half[k]))
