"""Compiled broadphase of the collision world: link poses for a batch of configurations and
geometric proofs that settle most pairs without python-fcl.

A robot link is a cylinder (radius r, half-length h about its local z axis). Each checked pair
gets one of three verdicts (:func:`classify`): CLEAR (provably apart), CONTACT (provably
overlapping) or UNDECIDED, which goes to python-fcl, the exact judge (:mod:`.collision`).

CONTACT is proven with balls that lie inside both shapes and overlap by more than ``MARGIN``
(0.1 mm): a certainty about the exact shapes, far outside any exact test's tolerance. The balls
have radius min(r, h) with centres on the cylinder's axis, or, for a rim, radius 0.2 mm at the
shrunk cylinder's deepest points (:func:`.gaps.rim_box_contact`,
:func:`.gaps.rim_cylinders_contact`). Meshes never get CONTACT (python-fcl sees a
mesh as a surface). CLEAR is a separating-axis or distance argument that holds for the exact
shapes, with a margin of ``EPS`` metres against rounding:

* link-link and link-cylinder obstacle: the capsules (segment + radius) that enclose both
  cylinders are farther apart than the sum of their radii; a cylinder obstacle's box too (as
  a box, below);
* link-sphere: the link's capsule axis is farther from the sphere's centre than r + R;
* link-box (and link-mesh, through the box that bounds the mesh in its own frame): an axis
  among the box's three face normals, the cylinder's axis, the three cross products of the
  two, and the line between the centres, on which the projections of the exact cylinder
  (|u.z| h + r sqrt(1 - (u.z)^2)) and of the box (sum |u.b_i| e_i) do not overlap;
* a mesh body's pair that its cylinder leaves undecided: the balls around its surface, all
  apart from the other body (:mod:`.bounds_balls`).

In a segment's walk (:mod:`.bounds_walk`), a body-obstacle pair closes by how far the body's
points move per step, a body-body pair only by the joints between the two bodies
(:func:`_closing`).

Forward kinematics is the product of exponentials of the chain's joints (space frame), the same
representation as :mod:`.poe`; Pinocchio stays the reference it is tested against.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning import bounds_balls, scene_tree
from usar_arm.planning.bounds_arrays import (
    BOUND,
    BOX,
    CAPSULE,
    COVER_FROM,
    COVER_TO,
    GROUP,
    GROUP_RADIUS,
    HALF,
    HULL,
    JOINT_WIDTH,
    MOVED,
    NEXT,
    O_BOUND,
    O_CENTRE,
    OWNER,
    RADIUS,
    REACH,
    RHO,
    SOLID,
    SPHERE,
    IndexArray,
    Packed,
    link_poses,
    pack,
    poses_into,
    prepare_links,
    prepare_obstacles,
)
from usar_arm.planning.bounds_scene import CLEAR, CONTACT, UNDECIDED, judge_scene
from usar_arm.planning.gaps import rim_cylinders_contact, rows_distance, segment_distance
from usar_arm.planning.jit import inline_kernel, kernel

__all__ = [
    "BOX",
    "CAPSULE",
    "CLEAR",
    "CONTACT",
    "COVER_FROM",
    "COVER_TO",
    "EPS",
    "GROUP",
    "GROUP_RADIUS",
    "HULL",
    "MARGIN",
    "NEXT",
    "OWNER",
    "SOLID",
    "SPHERE",
    "UNDECIDED",
    "axis_segments",
    "check",
    "classify",
    "judge_pairs",
    "link_poses",
    "pack",
    "segment_distance",
    "summary",
    "summary_packed",
    "warm_up",
]

VerdictArray = np.ndarray[Any, np.dtype[np.int8]]
"""Per-pair verdicts (CLEAR, CONTACT, UNDECIDED)."""

REFINE = 8.0
"""In a segment's walk, a pair whose quick clearance bound would skip fewer than this many
steps gets the tighter (and costlier) bound too."""
EPS = 1e-9
"""Safety margin (m): a pair is cleared only when separated by more than this."""
MARGIN = 1e-4
"""A pair is proven in contact only when balls inside both shapes overlap by more than this
(m): far beyond the tolerance of any exact test, so python-fcl always agrees."""



@kernel
def axis_segments(world: Array, links: Array, seg: Array) -> None:
    """Fill ``seg`` (6, L, 3) from one configuration's link poses ``world`` (L, 3, 4): each
    cylinder's axis segment (start, direction), its inner balls' segment, its axis, its centre."""
    for k in range(world.shape[0]):
        half, reach = links[k, HALF], links[k, REACH]
        for a in range(3):
            z, centre = world[k, a, 2], world[k, a, 3]
            seg[0, k, a] = centre - z * half
            seg[1, k, a] = 2.0 * z * half
            seg[2, k, a] = centre - z * reach
            seg[3, k, a] = 2.0 * z * reach
            seg[4, k, a] = z
            seg[5, k, a] = centre


@inline_kernel
def judge_pairs(seg: Array, world: Array, packed: Packed, eps: float, margin: float,
                move: Array, cum: Array, refine: float, cap: float, out: VerdictArray,
                cand: Array, scratch: Array, stack: IndexArray,
                balls: tuple[Array, Array, np.ndarray]) -> tuple[float, float]:
    """Verdicts on every pair of one configuration (into ``out`` (P + Q,)), and, over the
    cleared link-link and link-obstacle pairs, the smallest lower bound of a pair's clearance
    divided by how far the pair can close per unit of motion: how many units of motion cannot
    bring any pair into contact (0 when a pair is not cleared; inf when there is none).
    ``move`` (L,): per body, how far its points can move (a body-obstacle pair closes by that);
    ``cum`` (L, n + 1): per body, how far joints 0 .. J - 1 can move its points, summed over
    the joints (a body-body pair closes only by the joints between them, :func:`_closing`).
    ``cap``: the scene's value is at most this (inf: none), and nothing that could only show
    it above the cap is computed (a walk never proves more than its horizon).

    Two kernels, each called once per configuration (a call per pair costs more than the
    test itself): :func:`_judge_links` and :func:`.bounds_scene.judge_scene`; both give a pair
    their cylinders leave undecided a second look with the mesh bodies' balls
    (:mod:`.bounds_balls`; ``balls``: their world centres and which bodies are placed, scratch
    of the caller's, reset here). ``world`` (L, 3, 4): the bodies' poses; ``packed``: the
    collision world's arrays (:class:`.bounds_arrays.Packed`)."""
    balls[2][:] = 0
    self_gap = _judge_links(seg, world, packed.links, packed.pairs, packed.n_rr, packed.groups,
                            packed.leaves, eps, margin, cum, cap, out, scratch, balls)
    for p in range(packed.n_rr, packed.pairs.shape[0]):
        out[p] = CLEAR
    if packed.nodes.shape[0] == 0:
        return self_gap, math.inf
    return self_gap, judge_scene(seg, world, packed.links, packed.kind, packed.obstacles,
                                  packed.axes, packed.tree, packed.nodes, packed.order,
                                  packed.pair_of, packed.groups, packed.leaves, eps, margin, move,
                                  refine, cap, out, cand, scratch, stack, balls)


@inline_kernel
def _judge_links(seg: Array, world: Array, links: Array, pairs: IndexArray, n_rr: int,
                 groups: Array, leaves: Array, eps: float, margin: float, cum: Array,
                 cap: float, out: VerdictArray, scratch: Array,
                 balls: tuple[Array, Array, np.ndarray]) -> float:
    """:func:`judge_pairs` on the link-link pairs (the first ``n_rr``): their verdicts and the
    smallest cleared gap per unit of closing motion (0 when a pair is not cleared; at most
    ``cap``). A pair's gap is the larger of two lower bounds, the spheres about the two bodies
    and the capsules about their cylinders; the spheres alone clear a pair they show apart by
    no less than the smallest gap found so far (they cannot lower it).
    ``scratch`` (3,): a point, for the rim proofs."""
    self_gap = cap
    p = 0
    while p < n_rr:
        # The block of rows of one link pair (rows sorted by the links' indices): when both
        # links are grouped, the capsules around their groups clear the whole block at once.
        i, j = pairs[p, 0], pairs[p, 1]
        end = p + 1
        while (end < n_rr and links[pairs[end, 0], OWNER] == links[i, OWNER]
               and links[pairs[end, 1], OWNER] == links[j, OWNER]):
            end += 1
        gi, gj = int(links[i, GROUP]), int(links[j, GROUP])
        if end - p > 1 and gi >= 0 and gj >= 0:
            gap = (rows_distance(seg, 0, gi, gj)
                   - links[gi, GROUP_RADIUS] - links[gj, GROUP_RADIUS])
            if gap > eps:
                closing = 0.0
                for r in range(p, end):
                    out[r] = CLEAR
                    closing = max(closing, _closing(cum, links, pairs[r, 0], pairs[r, 1]))
                if closing > 0.0:
                    self_gap = min(self_gap, gap / closing)
                p = end
                continue
        for r in range(p, end):
            i, j = pairs[r, 0], pairs[r, 1]
            closing = _closing(cum, links, i, j)
            apart = (math.sqrt((seg[5, i, 0] - seg[5, j, 0]) ** 2
                               + (seg[5, i, 1] - seg[5, j, 1]) ** 2
                               + (seg[5, i, 2] - seg[5, j, 2]) ** 2)
                     - links[i, BOUND] - links[j, BOUND])
            if apart > eps and (closing == 0.0 or apart >= self_gap * closing):
                out[r] = CLEAR  # (the spheres about them: apart, and by no less than found)
                continue
            gap = max(apart, rows_distance(seg, 0, i, j) - links[i, RADIUS] - links[j, RADIUS])
            if gap <= eps:  # proven in contact, or the balls of a mesh body have a look
                inner = rows_distance(seg, 2, i, j)
                if inner < links[i, RHO] + links[j, RHO] - margin or (
                        links[i, SOLID] > 0.5 and links[j, SOLID] > 0.5 and rim_cylinders_contact(
                            seg[5, i], seg[4, i], links[i, RADIUS], links[i, HALF], seg[5, j],
                            seg[4, j], links[j, RADIUS], links[j, HALF], margin, scratch)):
                    out[r] = CONTACT
                    self_gap = 0.0
                    continue
                gap = bounds_balls.bodies_gap(i, j, seg, world, links, groups, leaves, eps,
                                              balls)
            if gap > eps:
                out[r] = CLEAR
                if closing > 0.0:
                    self_gap = min(self_gap, gap / closing)
                continue
            out[r] = UNDECIDED
            self_gap = 0.0
        p = end
    return self_gap


@inline_kernel
def _closing(cum: Array, links: Array, i: int, j: int) -> float:
    """How far bodies ``i`` and ``j`` can close per unit of motion: the joints that move both
    move them together (the first ``MOVED`` joints move a body), so only those between them
    count, by how far they move the farther body's points (``cum`` as :func:`judge_pairs`)."""
    a, b = int(links[i, MOVED]), int(links[j, MOVED])
    if a <= b:
        return cum[j, b] - cum[j, a]
    return cum[i, a] - cum[i, b]


def ball_scratch(links: Array, groups: Array, leaves: Array
                 ) -> tuple[Array, Array, np.ndarray]:
    """The scratch of :func:`judge_pairs`'s balls: their world centres (groups, leaves) and the
    flags of what is placed (bodies' groups, then groups' leaves: see :mod:`.bounds_balls`)."""
    return (np.empty((groups.shape[0], 3)), np.empty((leaves.shape[0], 3)),
            np.zeros(links.shape[0] + groups.shape[0], dtype=np.int8))


ball_scratch_kernel = kernel(ball_scratch)


@kernel
def _still(links: Array) -> tuple[Array, Array]:
    """``move`` and ``cum`` of :func:`judge_pairs` for a single configuration: zeros (nothing moves,
    so only whether a pair is cleared matters, and the sphere tree prunes every subtree its
    bound clears by ``eps``; the gaps returned are then inf)."""
    depth = 0
    for k in range(links.shape[0]):
        depth = max(depth, int(links[k, MOVED]))
    return np.zeros(links.shape[0]), np.zeros((links.shape[0], depth + 1))


@kernel
def _verdicts(world: Array, packed: Packed, eps: float, margin: float
              ) -> tuple[VerdictArray, VerdictArray]:
    """Verdicts (N, P + Q) int8 on the pairs (link-link pairs first, then link-obstacle) at the
    link poses ``world`` (N, L, 3, 4), and each configuration's (N,) (:func:`_row_verdict`),
    over the collision world's arrays ``packed`` (its joints and zero poses unused)."""
    n_cfg, n_link = world.shape[0], world.shape[1]
    out = np.zeros((n_cfg, packed.pairs.shape[0]), dtype=np.int8)
    overall = np.empty(n_cfg, dtype=np.int8)
    seg = np.empty((6, n_link, 3))
    cand = np.empty((8, 3))
    scratch = np.empty(3)
    stack = np.empty(max(1, packed.nodes.shape[0]), dtype=np.int64)
    move, cum = _still(packed.links)
    balls = ball_scratch_kernel(packed.links, packed.groups, packed.leaves)
    for c in range(n_cfg):
        axis_segments(world[c], packed.links, seg)
        judge_pairs(seg, world[c], packed, eps, margin, move, cum, 0.0, math.inf, out[c], cand,
                    scratch, stack, balls)
        overall[c] = _row_verdict(out[c])
    return out, overall


@inline_kernel
def _row_verdict(row: VerdictArray) -> int:
    """One configuration's verdict from its pairs': CONTACT when one is proven in contact,
    else UNDECIDED when one is undecided, else CLEAR."""
    verdict = CLEAR
    for p in range(row.shape[0]):
        if row[p] == CONTACT:
            return CONTACT
        if row[p] == UNDECIDED:
            verdict = UNDECIDED
    return verdict


def classify(world: Array, radius: Array, half: Array, rr: IndexArray, rs: IndexArray,
             kind: IndexArray, pose: Array, size: Array, eps: float, margin: float
             ) -> VerdictArray:
    """Verdicts (N, P + Q) int8 (CLEAR, CONTACT, UNDECIDED) on every checked pair.

    ``world`` (N, L, 3, 4): link cylinder poses (axis = local z); ``radius``/``half`` (L,);
    ``rr`` (P, 2) link-link pairs; ``rs`` (Q, 2) link-obstacle pairs; ``kind`` (S,) obstacle
    kinds (BOX, SPHERE, CAPSULE, HULL); ``pose`` (S, 3, 4) obstacle poses; ``size`` (S, 3):
    box half extents, sphere radius in [0], cylinder radius and half-length in [0], [1].

    CLEAR needs a separation above ``eps`` between enclosing volumes; CONTACT needs balls
    inside both shapes that overlap by more than ``margin`` (m), so that any exact test agrees.
    """
    links = prepare_links(radius, half, np.zeros(radius.shape[0], dtype=np.int64))
    obstacles, axes = prepare_obstacles(kind, pose, size)
    pairs = np.ascontiguousarray(np.vstack([rr.reshape(-1, 2), rs.reshape(-1, 2)]),
                                 dtype=np.int64)
    tree, nodes, order = scene_tree.build(obstacles[:, O_CENTRE:O_CENTRE + 3],
                                          obstacles[:, O_BOUND])
    pair_of = scene_tree.pair_table(rs, len(rr), len(radius), len(kind))
    packed = Packed(np.zeros((0, JOINT_WIDTH)), np.zeros((len(radius), 4, 4)), links, pairs,
                    int(rr.shape[0]), kind, obstacles, axes, tree, nodes, order, pair_of,
                    np.zeros((0, 6)), np.zeros((0, 4)))
    return _verdicts(world, packed, eps, margin)[0]


@kernel
def check(qs: Array, packed: Packed, eps: float, margin: float
          ) -> tuple[Array, VerdictArray, VerdictArray]:
    """Link cylinder poses (N, L, 3, 4), pair verdicts (N, P + Q) and each configuration's
    verdict (N,) (CLEAR, CONTACT or UNDECIDED, as :func:`summary`) for configurations ``qs``
    (N, n) in one call, from the arrays :func:`pack` prepares once per collision world."""
    world = link_poses(qs, packed.joints, packed.zero, packed.links)
    verdicts, overall = _verdicts(world, packed, eps, margin)
    return world, verdicts, overall


@kernel
def summary(q: Array, world: Array, row: VerdictArray, joints: Array, zero: Array,
            links: Array, pairs: IndexArray, n_rr: int, kind: IndexArray, obstacles: Array,
            axes: Array, tree: Array, nodes: IndexArray, order: IndexArray, pair_of: IndexArray,
            groups: Array, leaves: Array, eps: float, margin: float) -> int:
    """:func:`summary_packed`, called from Python with the fields of a :class:`Packed` one by
    one (``*packed``): numba's dispatcher types a named tuple argument in Python, about 1 us a
    call (measured in the collision stage: 3.9 -> 5.0 us a single query), and arrays in C; the
    kernel puts the named tuple together itself."""
    return summary_packed(q, world, row, Packed(joints, zero, links, pairs, n_rr, kind,
                                                obstacles, axes, tree, nodes, order, pair_of,
                                                groups, leaves), eps, margin)


@inline_kernel
def summary_packed(q: Array, world: Array, row: VerdictArray, packed: Packed, eps: float,
                   margin: float) -> int:
    """One configuration ``q`` (n,) in one call: the link cylinder poses into ``world``
    (L, 3, 4) and the pair verdicts into ``row`` (P + Q,), both the caller's, and one verdict:
    CLEAR when every pair is cleared, CONTACT when one is proven in contact, else UNDECIDED
    (``world`` and ``row`` are then what the exact judge needs)."""
    links = packed.links
    n, n_link = q.shape[0], packed.zero.shape[0]
    frames = np.empty((n + 1, 3, 4))
    seg = np.empty((6, n_link, 3))
    row[:] = CLEAR
    stack = np.empty(max(1, packed.nodes.shape[0]), dtype=np.int64)
    poses_into(q, packed.joints, packed.zero, links, frames, world)
    axis_segments(world, links, seg)
    move, cum = _still(links)
    judge_pairs(seg, world, packed, eps, margin, move, cum, 0.0, math.inf, row, np.empty((8, 3)),
                np.empty(3), stack, ball_scratch_kernel(links, packed.groups, packed.leaves))
    return _row_verdict(row)


def warm_up() -> None:
    """Compile :func:`check` and :func:`summary` for the argument types the
    collision world passes (numba caches the machine code on disk, so later processes load it
    instead of compiling for ~20 s).
    Run once after installing (``make demo`` and ``make test`` do):
    ``python -c "from usar_arm.planning.bounds import warm_up; warm_up()"``."""
    eye = np.eye(4)
    packed = pack(np.array([[0.0, 0.0, 1.0]]), np.zeros((1, 3)), np.array([1]), eye[None],
                  np.array([0.1]), np.array([0.2]), np.array([1]), np.zeros((0, 2), np.int64),
                  np.array([[0, 0]], np.int64), np.array([BOX]), eye[None, :3, :],
                  np.array([[0.5, 0.5, 0.5]]))
    check(np.zeros((1, 1)), packed, EPS, MARGIN)
    summary(np.zeros(1), np.empty((1, 3, 4)), np.empty(1, np.int8), *packed, EPS, MARGIN)
