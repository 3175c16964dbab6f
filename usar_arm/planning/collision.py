"""Collision checking of the arm against itself and a scene.

The robot's links are the URDF's cylinders (optionally padded); pairs the SRDF disables are never
checked. :class:`CollisionWorld` puts two judges together: the compiled verdicts
(:mod:`.verdicts`, kernels in :mod:`.bounds`) clear the pairs that provably cannot touch and
prove deep contacts, for one configuration, a batch or a segment; the exact checks
(:mod:`.exact`, the only module that imports python-fcl) decide the rest.
:meth:`CollisionWorld.contacts_brute_force` checks every pair with FCL directly and is the
reference the compiled path is tested against.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.model import KinematicChain
from usar_arm.core.shapes import CylinderShape, Mesh, Shape
from usar_arm.core.spatial import Array, invert
from usar_arm.planning import bounds
from usar_arm.planning.ball_cover import cover_in
from usar_arm.planning.bounds_arrays import Cover
from usar_arm.planning.element_fit import bounding_cylinder, padded
from usar_arm.planning.exact import ExactJudge
from usar_arm.planning.inner_balls import axis_balls_in
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.planning.never import proven_never
from usar_arm.planning.scene import EMPTY, Scene
from usar_arm.planning.verdicts import CompiledVerdicts

Pair = tuple[str, str]

def pair(a: str, b: str) -> Pair:
    """A link/object pair in canonical (sorted) order."""
    return (a, b) if a <= b else (b, a)


@dataclass(frozen=True)
class Contact:
    """Two bodies in contact and how deep (m; 0 when FCL reports no depth)."""

    a: str
    b: str
    depth: float


@dataclass(frozen=True, eq=False)
class _Body:
    """One collision element of a link as the two judges see it: the compiled verdicts its
    bounding cylinder (``local``: pose in the link frame; radius, half-length, m; ``exact``:
    contact proofs allowed), FCL its shape (``to_shape``: the shape's pose in the cylinder's
    frame, None when the same); a mesh's also its balls in the cylinder's frame
    (:data:`.bounds_arrays.Cover`): the groups and leaves around its surface
    (:mod:`.ball_cover`), which clear pairs its cylinder cannot, and the balls inside it
    (:mod:`.inner_balls`, (K, 4); none when it is not closed), which prove contacts with
    obstacles."""

    link: str
    shape: Shape
    local: Array
    radius: float
    half: float
    exact: bool
    to_shape: Array | None
    balls: Cover | None = None


def _bodies(chain: KinematicChain, padding: float) -> list[_Body]:
    """Every collision element of the chain's links, in link order."""
    out = []
    for lk in chain.links:
        for c in lk.elements:
            s = c.shape
            if isinstance(s, CylinderShape):  # the learnt arms' cylinders, as they always were
                out.append(_Body(lk.name, CylinderShape(s.radius + padding, s.length
                                                        + 2 * padding), c.origin.matrix(),
                                 s.radius + padding, s.length / 2 + padding, True, None))
                continue
            grown = padded(s, padding)
            fit = bounding_cylinder(grown)
            same = bool(np.array_equal(fit.frame, np.eye(4)))
            to_shape = None if same else invert(fit.frame)
            balls: Cover | None = None
            if isinstance(grown, Mesh):
                cover = cover_in(grown.vertices, grown.faces, to_shape)
                balls = (cover.groups, cover.leaves,
                         axis_balls_in(grown.vertices, grown.faces, to_shape, fit.half))
            out.append(_Body(lk.name, grown, c.origin.matrix() @ fit.frame, fit.radius,
                             fit.half, fit.exact, to_shape, balls))
    return out


class CollisionWorld:
    """The arm (its links' collision elements) and a scene.

    Broadphase: a compiled kernel (:mod:`.bounds`) computes every link's pose for a batch of
    configurations and clears the checked pairs that provably cannot touch (enclosing capsules,
    separating axes of the exact cylinder against boxes); only the pairs it cannot clear reach
    FCL's exact narrowphase (:mod:`.exact`).

    Args:
        chain: the robot description (link cylinders).
        kinematics: its Pinocchio model (link poses).
        disabled: link pairs never checked (the SRDF's disable_collisions).
        scene: obstacles in base_link (default: none).
        padding: safety margin (m) added to every robot cylinder's radius and half-length.
        never: the robot-robot pairs proven never in contact for this chain and padding, when
            known already (:attr:`never` of another world of the arm); else proven here.
    """

    def __init__(self, chain: KinematicChain, kinematics: KinematicModel,
                 disabled: Iterable[Pair] = (), scene: Scene = EMPTY, padding: float = 0.0,
                 never: Iterable[Pair] | None = None):
        self.chain = chain
        self.kinematics = kinematics
        self.scene = scene
        self.padding = float(padding)
        bodies = _bodies(chain, self.padding)
        self._links = [b.link for b in bodies]
        self._frame_ids = [kinematics.frame_id(n) for n in self._links]
        self._local = np.array([b.local for b in bodies]).reshape(-1, 4, 4)
        self._radius = np.array([b.radius for b in bodies])
        self._half = np.array([b.half for b in bodies])
        self._poses = np.zeros((len(self._links), 4, 4))
        self._compiled = CompiledVerdicts(chain, self._links, self._radius, self._half,
                                          self._local, scene,
                                          np.array([b.exact for b in bodies], dtype=bool),
                                          [b.balls for b in bodies],
                                          np.array([isinstance(b.shape, CylinderShape)
                                                    for b in bodies], dtype=bool))
        self._exact = ExactJudge([b.shape for b in bodies], [b.to_shape for b in bodies],
                                 self._radius, self._half, scene)
        self._levers: Array | None = None
        disabled = {pair(a, b) for a, b in disabled}
        self.never = set(never) if never is not None else self._prove_never(disabled)
        self.set_disabled(disabled)

    def _prove_never(self, disabled: set[Pair]) -> set[Pair]:
        """Robot-robot pairs, of those not ``disabled``, proven never in contact over a joint's
        whole range (:mod:`.never`: links that one revolute joint alone moves against each
        other)."""
        names = sorted(set(self._links))
        reach = np.hypot(self._radius, self._half)

        def centres(q: Array) -> Array:
            self.set_configuration(q)
            return np.array(self._world[:, :3, 3])

        def gap(q: Array, body_pairs: list[tuple[int, int]]) -> float:
            self.set_configuration(q)
            return self._exact.distance(self._world, np.array(body_pairs, dtype=np.int64),
                                        np.zeros((0, 2), dtype=np.int64))

        candidates = [(a, b) for i, a in enumerate(names) for b in names[i + 1:]
                      if (a, b) not in disabled]
        return {pair(a, b) for a, b in
                proven_never(self.chain, self._links, centres, reach, candidates, gap)}

    def in_scene(self, scene: Scene) -> CollisionWorld:
        """The same arm (geometry, disabled pairs, padding) in another scene: only the scene's
        part is built, so a study that moves the scene around the arm (base placement) pays
        for the obstacles alone."""
        other = copy.copy(self)
        other.scene = scene
        other._poses = np.zeros_like(self._poses)
        other._compiled = self._compiled.in_scene(scene)
        other._exact = self._exact.in_scene(scene)
        other.set_disabled(self.disabled)
        return other

    @property
    def verdicts(self) -> CompiledVerdicts:
        """The compiled verdicts of this world (what the compiled planner searches over)."""
        return self._compiled

    def bounded_poses(self, qs: Array) -> tuple[Array, NDArray[np.int8]]:
        """World poses (N, L, 3, 4) of the link cylinders at configurations ``qs`` (N, n), and
        (N, P + Q) verdicts of the compiled tests on the robot-robot then robot-scene pairs:
        :data:`~.bounds.CLEAR`, :data:`~.bounds.CONTACT` or :data:`~.bounds.UNDECIDED` (for
        FCL)."""
        world, verdicts, _ = self._compiled.check(qs)
        return world, verdicts

    # ------------------------------------------------------------------ state
    def set_disabled(self, pairs: Iterable[Pair]) -> None:
        """Replace the set of robot-robot pairs that are never checked."""
        self.disabled = {pair(a, b) for a, b in pairs}
        allowed = {pair(link, o.name) for o in self.scene.objects for link in o.allow}
        self._skip = self.disabled | allowed | self.never
        n = len(self._links)
        rr = [(i, j) for i in range(n) for j in range(i + 1, n)
              if self._links[i] != self._links[j]
              and pair(self._links[i], self._links[j]) not in self._skip]
        rs = [(i, k) for i in range(n) for k, o in enumerate(self.scene.objects)
              if pair(self._links[i], o.name) not in self._skip]
        self._compiled.check_pairs(np.array(rr, dtype=np.int64), np.array(rs, dtype=np.int64))
        self._rr, self._rs = self._compiled.rr, self._compiled.rs

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
        return self._compiled.link_levers()

    @property
    def link_names(self) -> tuple[str, ...]:
        """Links that have collision geometry."""
        return tuple(dict.fromkeys(self._links))

    def checked_pairs(self) -> list[Pair]:
        """Every robot-robot and robot-scene pair that is checked (not disabled or allowed)."""
        return sorted({self._pair_name(p) for p in range(len(self._rr) + len(self._rs))})

    def set_configuration(self, q: Array) -> None:
        """Place the robot's cylinders at configuration ``q`` (rad/m)."""
        self.kinematics.update(q)
        oMf = self.kinematics.data.oMf
        for k, fid in enumerate(self._frame_ids):
            self._poses[k] = oMf[fid].homogeneous
        self._world = self._poses @ self._local

    # ------------------------------------------------------------------ queries
    def in_collision(self, q: Array) -> bool:
        """True when any checked pair overlaps at ``q``."""
        quick, world, verdicts = self._compiled.summary(q)
        if quick != bounds.UNDECIDED:
            return bool(quick == bounds.CONTACT)
        return self._any_contact(world, verdicts)

    def contacts(self, q: Array) -> list[Pair]:
        """Every checked pair in contact at ``q``, sorted."""
        world, verdicts = self.bounded_poses(q)
        return sorted(set(self._decide(world[0], verdicts[0])))

    def _decide(self, poses: Array, verdicts: NDArray[np.int8]) -> list[Pair]:
        """The pairs in contact, given the compiled verdicts (link poses (L, 3, 4))."""
        return [self._pair_name(p) for p in
                self._exact.undecided(poses, verdicts, self._rr, self._rs)]

    def _any_contact(self, poses: Array, verdicts: NDArray[np.int8]) -> bool:
        """Whether a pair is in contact, given the compiled verdicts (FCL on the undecided
        ones, stopping at the first contact)."""
        return self._exact.any_contact(poses, verdicts, self._rr, self._rs)

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
        checked: list[tuple[bool, int, int]] = []
        names: list[Pair] = []
        for i, a in enumerate(self._links):
            others = [(False, j, self._links[j]) for j in range(i + 1, len(self._links))
                      if self._links[j] != a]
            others += [(True, k, o.name) for k, o in enumerate(self.scene.objects)]
            for static, j, b in others:
                if pair(a, b) not in self._skip:
                    checked.append((static, i, j))
                    names.append(pair(a, b))
        return sorted({names[n] for n in self._exact.every_pair(self._world, checked)})

    def contact_details(self, q: Array) -> list[Contact]:
        """The pairs in contact at ``q`` with their penetration depth (m)."""
        self.set_configuration(q)
        index: dict[str, list[tuple[bool, int]]] = {}
        for i, n in enumerate(self._links):
            index.setdefault(n, []).append((False, i))
        index.update({o.name: [(True, k)] for k, o in enumerate(self.scene.objects)})
        return [Contact(a, b, max(self._exact.depth(self._world, x, y)
                                  for x in index[a] for y in index[b]))
                for a, b in self.contacts(q)]

    def distance(self, q: Array) -> float:
        """Minimum clearance (m) over the checked pairs at ``q`` (0 or less in contact).

        Pairs are visited in order of their AABB gap (a lower bound of their distance) and the
        search stops when the next gap exceeds the best distance found.
        """
        self.set_configuration(q)
        return self._exact.distance(self._world, self._rr, self._rs)

    # ------------------------------------------------------------------ batches
    def in_collision_many(self, qs: Array) -> Array:
        """:meth:`in_collision` for N configurations (N, n) at once -> bool (N,).

        Forward kinematics of every link and the bounding-volume tests run compiled over the
        whole batch; FCL's narrowphase runs only for the pairs they could not clear, stopping
        at a configuration's first contact. The fast path for edges and trajectories.
        """
        world, verdicts, overall = self._compiled.check(qs)
        hit = overall == bounds.CONTACT
        for n in np.flatnonzero(overall == bounds.UNDECIDED):
            hit[n] = self._any_contact(world[n], verdicts[n])
        return hit

    def segment_free(self, a: Array, b: Array, steps: int) -> bool:
        """True when none of the ``steps + 1`` evenly spaced configurations from ``a`` to ``b``
        (both included) is in collision: the answer of checking every one of them.

        The compiled walk (:mod:`.bounds_walk`) checks them coarse to fine (the ends, the
        middle, the quarters...), each evaluated configuration proving free those within its
        clearance on both sides, so a blocked segment ends at one of its first evaluations and
        a free one needs few; a configuration it leaves undecided goes to FCL at once.
        """
        if steps < 1:
            raise ValueError(f"a segment needs at least 1 step, got {steps}")
        return self._compiled.segment_free(a, b, steps, self._any_contact)[0]

    def contacts_many(self, qs: Array) -> list[list[Pair]]:
        """:meth:`contacts` for N configurations at once."""
        world, verdicts = self.bounded_poses(qs)
        found: list[list[Pair]] = [[] for _ in range(len(world))]
        for n in np.flatnonzero(verdicts.any(axis=1)):
            found[n] = sorted(set(self._decide(world[n], verdicts[n])))
        return found
