"""Compiled broadphase of the collision world: link poses for a batch of configurations and
geometric proofs that settle most pairs without python-fcl.

A robot link is a cylinder (radius r, half-length h about its local z axis). Each checked pair
gets one of three verdicts (:func:`classify`): CLEAR (provably apart), CONTACT (provably
overlapping) or UNDECIDED, which goes to python-fcl, the exact judge (:mod:`.collision`).

CONTACT is proven with balls that lie inside both shapes (radius min(r, h), centres on the
cylinder's axis) and overlap by more than ``MARGIN`` (0.1 mm): a certainty about the exact
shapes, far outside any exact test's tolerance. Meshes never get CONTACT (python-fcl sees a
mesh as a surface). CLEAR is a separating-axis or distance argument that holds for the exact
shapes, with a margin of ``EPS`` metres against rounding:

* link-link and link-cylinder obstacle: the capsules (segment + radius) that enclose both
  cylinders are farther apart than the sum of their radii;
* link-sphere: the link's capsule axis is farther from the sphere's centre than r + R;
* link-box (and link-mesh, through the box that bounds the mesh in its own frame): an axis
  among the box's three face normals, the cylinder's axis, the three cross products of the
  two, and the line between the centres, on which the projections of the exact cylinder
  (|u.z| h + r sqrt(1 - (u.z)^2)) and of the box (sum |u.b_i| e_i) do not overlap.

Forward kinematics is the product of exponentials of the chain's joints (space frame), the same
representation as :mod:`.poe`; Pinocchio stays the reference it is tested against.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning import scene_tree
from usar_arm.planning.jit import kernel

IndexArray = np.ndarray[Any, np.dtype[np.int64]]
"""Integer arrays (pair indices, kinds)."""
VerdictArray = np.ndarray[Any, np.dtype[np.int8]]
"""Per-pair verdicts (CLEAR, CONTACT, UNDECIDED)."""

REFINE = 8.0
"""In a walk, a pair whose quick clearance bound would skip fewer than this many steps gets the
tighter (and costlier) bound too."""
EPS = 1e-9
"""Safety margin (m): a pair is cleared only when separated by more than this."""
MARGIN = 1e-4
"""A pair is proven in contact only when balls inside both shapes overlap by more than this
(m): far beyond the tolerance of any exact test, so python-fcl always agrees."""

BOX, SPHERE, CAPSULE, HULL = 0, 1, 2, 3
"""Obstacle kinds: an oriented box (half extents), a sphere (radius), a cylinder (radius,
half-length; its enclosing capsule clears pairs), and a triangle mesh's bounding box (it can
clear a pair but never proves a contact: python-fcl treats a mesh as a surface)."""


@kernel
def _dot(a: Array, b: Array) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@kernel
def _poses_into(q: Array, joints: Array, zero: Array, links: Array, frames: Array,
                out: Array) -> None:
    """:func:`link_poses` of one configuration ``q`` (n,) into ``out`` (L, 3, 4), with
    ``frames`` (n + 1, 3, 4) as scratch: no allocation, for the hot loops."""
    n = q.shape[0]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
    t0 = t1 = t2 = 0.0
    frames[0] = 0.0
    frames[0, 0, 0] = frames[0, 1, 1] = frames[0, 2, 2] = 1.0
    for i in range(n):
        w0, w1, w2 = joints[i, 0], joints[i, 1], joints[i, 2]
        if joints[i, 6] > 0.5:
            a = q[i]
            sn, co = math.sin(a), math.cos(a)
            v = 1.0 - co
            e00, e01, e02 = co + w0 * w0 * v, w0 * w1 * v - w2 * sn, w0 * w2 * v + w1 * sn
            e10, e11, e12 = w1 * w0 * v + w2 * sn, co + w1 * w1 * v, w1 * w2 * v - w0 * sn
            e20, e21, e22 = w2 * w0 * v - w1 * sn, w2 * w1 * v + w0 * sn, co + w2 * w2 * v
            p0, p1, p2 = joints[i, 3], joints[i, 4], joints[i, 5]
            # t += R p - (R E) p = R (p - E p)
            d0 = p0 - (e00 * p0 + e01 * p1 + e02 * p2)
            d1 = p1 - (e10 * p0 + e11 * p1 + e12 * p2)
            d2 = p2 - (e20 * p0 + e21 * p1 + e22 * p2)
            t0 += r00 * d0 + r01 * d1 + r02 * d2
            t1 += r10 * d0 + r11 * d1 + r12 * d2
            t2 += r20 * d0 + r21 * d1 + r22 * d2
            r00, r01, r02 = (r00 * e00 + r01 * e10 + r02 * e20, r00 * e01 + r01 * e11
                             + r02 * e21, r00 * e02 + r01 * e12 + r02 * e22)
            r10, r11, r12 = (r10 * e00 + r11 * e10 + r12 * e20, r10 * e01 + r11 * e11
                             + r12 * e21, r10 * e02 + r11 * e12 + r12 * e22)
            r20, r21, r22 = (r20 * e00 + r21 * e10 + r22 * e20, r20 * e01 + r21 * e11
                             + r22 * e21, r20 * e02 + r21 * e12 + r22 * e22)
        else:
            x = q[i]
            t0 += (r00 * w0 + r01 * w1 + r02 * w2) * x
            t1 += (r10 * w0 + r11 * w1 + r12 * w2) * x
            t2 += (r20 * w0 + r21 * w1 + r22 * w2) * x
        f = frames[i + 1]
        f[0, 0], f[0, 1], f[0, 2], f[0, 3] = r00, r01, r02, t0
        f[1, 0], f[1, 1], f[1, 2], f[1, 3] = r10, r11, r12, t1
        f[2, 0], f[2, 1], f[2, 2], f[2, 3] = r20, r21, r22, t2
    for k in range(zero.shape[0]):
        f = frames[int(links[k, MOVED])]
        for row in range(3):
            for col in range(4):
                out[k, row, col] = (f[row, 0] * zero[k, 0, col] + f[row, 1] * zero[k, 1, col]
                                    + f[row, 2] * zero[k, 2, col])
            out[k, row, 3] += f[row, 3]


@kernel
def link_poses(qs: Array, joints: Array, zero: Array, links: Array) -> Array:
    """World poses (N, L, 3, 4) of L bodies at N configurations (N, n).

    ``joints`` (n, 7): each joint's axis and a point on it at the zero configuration, then 1
    for revolute or 0 for prismatic; ``zero`` (L, 4, 4) each body's pose at zero; ``links``
    (L, LINK_WIDTH) with how many joints (a prefix of the chain) move each body at MOVED.
    """
    n_cfg, n = qs.shape
    out = np.empty((n_cfg, zero.shape[0], 3, 4))
    frames = np.empty((n + 1, 3, 4))  # rotation | position after the first i joints
    for c in range(n_cfg):
        _poses_into(qs[c], joints, zero, links, frames, out[c])
    return out


@kernel
def segment_distance(p1: Array, d1: Array, p2: Array, d2: Array) -> float:
    """Distance (m) between the segments p1 + s d1 and p2 + t d2, s, t in [0, 1]
    (closest points of two segments, Ericson, Real-Time Collision Detection 5.1.9)."""
    r0, r1, r2 = p1[0] - p2[0], p1[1] - p2[1], p1[2] - p2[2]
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    f = d2[0] * r0 + d2[1] * r1 + d2[2] * r2
    tiny = 1e-300  # only a true zero length is a point: a 1e-9 m segment still counts
    if a <= tiny and e <= tiny:
        return math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    if a <= tiny:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = d1[0] * r0 + d1[1] * r1 + d1[2] * r2
        if e <= tiny:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = _dot(d1, d2)
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > tiny else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    x = r0 + d1[0] * s - d2[0] * t
    y = r1 + d1[1] * s - d2[1] * t
    z = r2 + d1[2] * s - d2[2] * t
    return math.sqrt(x * x + y * y + z * z)


@kernel
def _cylinder_box_gap(c: Array, z: Array, r: float, h: float, b_centre: Array,
                      b_axes: Array, b_half: Array, cand: Array) -> float:
    """The largest gap (m) between the projections of the cylinder (centre c, unit axis z,
    radius r, half-length h) and the box (centre, axes as rows (3, 3), half extents) on the
    candidate axes: a lower bound of their distance when positive (they are separated).
    ``cand`` (8, 3) is scratch space for the candidate axes."""
    d0, d1, d2 = c[0] - b_centre[0], c[1] - b_centre[1], c[2] - b_centre[2]
    count = 0
    for i in range(3):
        cand[count] = b_axes[i]
        count += 1
    cand[count] = z
    count += 1
    for i in range(3):
        b = b_axes[i]
        u0 = z[1] * b[2] - z[2] * b[1]
        u1 = z[2] * b[0] - z[0] * b[2]
        u2 = z[0] * b[1] - z[1] * b[0]
        norm = math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
        if norm > 1e-6:
            cand[count, 0], cand[count, 1], cand[count, 2] = u0 / norm, u1 / norm, u2 / norm
            count += 1
    dn = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if dn > 1e-9:
        cand[count, 0], cand[count, 1], cand[count, 2] = d0 / dn, d1 / dn, d2 / dn
        count += 1
    best = -math.inf
    for k in range(count):
        u = cand[k]
        uz = abs(_dot(u, z))
        cyl = uz * h + r * math.sqrt(max(0.0, 1.0 - uz * uz))
        box = (abs(_dot(u, b_axes[0])) * b_half[0] + abs(_dot(u, b_axes[1])) * b_half[1]
               + abs(_dot(u, b_axes[2])) * b_half[2])
        best = max(best, abs(u[0] * d0 + u[1] * d1 + u[2] * d2) - cyl - box)
    return best


@kernel
def _point_box_distance(x: Array, centre: Array, axes: Array, half: Array) -> float:
    """Distance (m) from the point ``x`` to the solid box (0 inside)."""
    total = 0.0
    for a in range(3):
        u = axes[a]
        t = abs((x[0] - centre[0]) * u[0] + (x[1] - centre[1]) * u[1]
                + (x[2] - centre[2]) * u[2]) - half[a]
        if t > 0.0:
            total += t * t
    return math.sqrt(total)


@kernel
def _inner_box_contact(c: Array, z: Array, rho: float, reach: float, b_centre: Array,
                       b_axes: Array, b_half: Array, margin: float, x: Array) -> bool:
    """True when a ball of radius ``rho`` inside the cylinder (its centre on the axis within
    ``reach`` of the centre ``c``) reaches more than ``margin`` into the box: a proof of
    contact. Tries the two ends of that segment and its point nearest the box's centre."""
    t = ((b_centre[0] - c[0]) * z[0] + (b_centre[1] - c[1]) * z[1]
         + (b_centre[2] - c[2]) * z[2])
    t = min(max(t, -reach), reach)
    for offset in (-reach, reach, t):
        for a in range(3):
            x[a] = c[a] + z[a] * offset
        if _point_box_distance(x, b_centre, b_axes, b_half) < rho - margin:
            return True
    return False


CLEAR, CONTACT, UNDECIDED = 0, 1, 2
"""Verdicts of :func:`classify` on a pair: provably apart, provably touching (by more than
the margin), or for the exact judge to decide."""

RADIUS, HALF, RHO, REACH, BOUND, MOVED = range(6)
LINK_WIDTH = 6
"""Columns of the per-link array: the cylinder's radius and half-length (m), the radius of the
balls inside it and how far their centres reach from its centre along the axis, the radius of a
sphere around it, and how many joints move it."""

O_SIZE, O_START, O_DIR, O_IN_START, O_IN_DIR, O_RHO, O_BOUND, O_CENTRE = (
    0, 3, 6, 9, 12, 15, 16, 17)
OBSTACLE_WIDTH = 20
"""Columns of the per-obstacle array: size (3), the enclosing segment's start and direction,
the inner balls' segment's start and direction, their radius, the radius of a sphere about the
centre that contains the obstacle, and the centre (3)."""


@kernel
def prepare_links(radius: Array, half: Array, moved_by: IndexArray) -> Array:
    """The per-link array (L, LINK_WIDTH) of cylinders of ``radius``/``half`` (m)."""
    out = np.empty((radius.shape[0], LINK_WIDTH))
    for k in range(radius.shape[0]):
        rho = min(radius[k], half[k])
        out[k, RADIUS], out[k, HALF], out[k, RHO] = radius[k], half[k], rho
        out[k, REACH] = half[k] - rho
        out[k, BOUND] = math.sqrt(radius[k] * radius[k] + half[k] * half[k])
        out[k, MOVED] = moved_by[k]
    return out


@kernel
def prepare_obstacles(kind: IndexArray, pose: Array, size: Array) -> tuple[Array, Array]:
    """The per-obstacle array (S, OBSTACLE_WIDTH) and the obstacles' axes as rows (S, 3, 3)
    of obstacles of ``kind`` at ``pose`` (S, 3, 4) with ``size`` (S, 3) (see :func:`classify`).
    """
    n_obj = kind.shape[0]
    out = np.zeros((n_obj, OBSTACLE_WIDTH))
    axes = np.empty((n_obj, 3, 3))
    for s in range(n_obj):
        for a in range(3):
            out[s, O_SIZE + a] = size[s, a]
        if kind[s] == CAPSULE:
            out[s, O_RHO] = min(size[s, 0], size[s, 1])
            out[s, O_BOUND] = math.sqrt(size[s, 0] ** 2 + size[s, 1] ** 2)
        elif kind[s] == SPHERE:
            out[s, O_RHO] = size[s, 0]
            out[s, O_BOUND] = size[s, 0]
        else:
            out[s, O_BOUND] = math.sqrt(size[s, 0] ** 2 + size[s, 1] ** 2 + size[s, 2] ** 2)
        for a in range(3):
            for b in range(3):
                axes[s, a, b] = pose[s, b, a]
            centre, z = pose[s, a, 3], pose[s, a, 2]
            out[s, O_CENTRE + a] = centre
            out[s, O_START + a] = centre
            out[s, O_IN_START + a] = centre
            if kind[s] == CAPSULE:
                out[s, O_START + a] = centre - z * size[s, 1]
                out[s, O_DIR + a] = 2.0 * z * size[s, 1]
                out[s, O_IN_START + a] = centre - z * (size[s, 1] - out[s, O_RHO])
                out[s, O_IN_DIR + a] = 2.0 * z * (size[s, 1] - out[s, O_RHO])
    return out, axes


@kernel
def _segments(world: Array, links: Array, seg: Array) -> None:
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


@kernel
def _judge(seg: Array, links: Array, pairs: IndexArray, n_rr: int, kind: IndexArray,
           obstacles: Array, axes: Array, tree: Array, nodes: IndexArray, order: IndexArray,
           pair_of: IndexArray, eps: float, margin: float, move: Array, refine: float,
           out: VerdictArray, cand: Array, scratch: Array, stack: IndexArray
           ) -> tuple[float, float]:
    """Verdicts on every pair of one configuration (into ``out`` (P + Q,)), and, over the
    cleared link-link and link-obstacle pairs, the smallest lower bound of a pair's clearance
    divided by how far the pair can close per unit of motion (``move`` (L,): per link, how
    far its points can move; a link-link pair closes by the sum of both): how many units of
    motion cannot bring any pair into contact (0 when a pair is not cleared; inf when there
    is none). With ``move`` all ones, these are the clearance bounds themselves (m).

    With a sphere tree over the obstacles (``tree``, ``nodes``, ``order`` of
    :func:`.scene_tree.build`, ``pair_of`` of :func:`.scene_tree.pair_table`; ``stack`` scratch
    of at least M entries), each link visits only the subtrees its bounding sphere comes within
    the current clearance bound (or ``eps``) of; the pairs below the others are CLEAR, farther
    apart than that bound. A pair whose quick bound is below ``refine`` units of its link's
    motion (at least ``eps`` m) gets the tighter test too, so a walk skips by a clearance bound
    closer to the truth."""
    self_gap, scene_gap = math.inf, math.inf
    for p in range(n_rr):
        i, j = pairs[p, 0], pairs[p, 1]
        gap = (segment_distance(seg[0, i], seg[1, i], seg[0, j], seg[1, j])
               - links[i, RADIUS] - links[j, RADIUS])
        if gap > eps:
            out[p] = CLEAR
            closing = move[i] + move[j]
            if closing > 0.0:
                self_gap = min(self_gap, gap / closing)
            continue
        inner = segment_distance(seg[2, i], seg[3, i], seg[2, j], seg[3, j])
        out[p] = CONTACT if inner < links[i, RHO] + links[j, RHO] - margin else UNDECIDED
        self_gap = 0.0
    for p in range(n_rr, pairs.shape[0]):
        out[p] = CLEAR
    if nodes.shape[0] == 0:
        return self_gap, scene_gap
    for i in range(pair_of.shape[0]):
        stack[0] = 0
        top = 1
        refine_i = max(eps, refine * move[i])
        while top > 0:
            top -= 1
            nd = stack[top]
            bound = (math.sqrt((seg[5, i, 0] - tree[nd, 0]) ** 2
                               + (seg[5, i, 1] - tree[nd, 1]) ** 2
                               + (seg[5, i, 2] - tree[nd, 2]) ** 2)
                     - tree[nd, 3] - links[i, BOUND])
            if bound > max(scene_gap * move[i], eps):
                continue  # every pair below is farther apart than the bound already found
            if nodes[nd, 0] >= 0:
                stack[top] = nodes[nd, 0]
                stack[top + 1] = nodes[nd, 1]
                top += 2
                continue
            for k in range(nodes[nd, 2], nodes[nd, 3]):
                s = order[k]
                p = pair_of[i, s]
                if p < 0:
                    continue
                # Written out here, not called: a kernel call per pair with these array
                # arguments costs more than the test itself.
                o = obstacles[s]
                if kind[s] == BOX or kind[s] == HULL:
                    # The link's centre against the solid box, less the link's bounding
                    # radius: tighter than two bounding spheres for a cell's large flat boxes.
                    gap = (_point_box_distance(seg[5, i], o[O_START:O_START + 3], axes[s],
                                               o[O_SIZE:O_SIZE + 3]) - links[i, BOUND])
                    if gap <= refine_i:
                        gap = max(gap, _cylinder_box_gap(
                            seg[5, i], seg[4, i], links[i, RADIUS], links[i, HALF],
                            o[O_START:O_START + 3], axes[s], o[O_SIZE:O_SIZE + 3], cand))
                else:
                    gap = (math.sqrt((seg[5, i, 0] - o[O_CENTRE]) ** 2
                                     + (seg[5, i, 1] - o[O_CENTRE + 1]) ** 2
                                     + (seg[5, i, 2] - o[O_CENTRE + 2]) ** 2)
                           - links[i, BOUND] - o[O_BOUND])
                    if gap <= refine_i:
                        gap = max(gap, segment_distance(seg[0, i], seg[1, i],
                                                        o[O_START:O_START + 3],
                                                        o[O_DIR:O_DIR + 3])
                                  - links[i, RADIUS] - o[O_SIZE])
                if gap > eps:
                    if move[i] > 0.0:
                        scene_gap = min(scene_gap, gap / move[i])
                    continue
                scene_gap = 0.0
                if kind[s] == BOX:
                    touching = _inner_box_contact(seg[5, i], seg[4, i], links[i, RHO],
                                                  links[i, REACH], o[O_START:O_START + 3],
                                                  axes[s], o[O_SIZE:O_SIZE + 3], margin,
                                                  scratch)
                elif kind[s] == HULL:
                    touching = False
                else:
                    inner = segment_distance(seg[2, i], seg[3, i],
                                             o[O_IN_START:O_IN_START + 3],
                                             o[O_IN_DIR:O_IN_DIR + 3])
                    touching = inner < links[i, RHO] + o[O_RHO] - margin
                out[p] = CONTACT if touching else UNDECIDED
    return self_gap, scene_gap


@kernel
def _verdicts(world: Array, links: Array, pairs: IndexArray, n_rr: int, kind: IndexArray,
              obstacles: Array, axes: Array, tree: Array, nodes: IndexArray, order: IndexArray,
              pair_of: IndexArray, eps: float, margin: float) -> VerdictArray:
    """Verdicts (N, P + Q) int8 on the pairs (link-link pairs first, then link-obstacle) at the
    link poses ``world`` (N, L, 3, 4); the prepared arrays of :func:`prepare_links`,
    :func:`prepare_obstacles` and :mod:`.scene_tree`."""
    n_cfg, n_link = world.shape[0], world.shape[1]
    out = np.zeros((n_cfg, pairs.shape[0]), dtype=np.int8)
    seg = np.empty((6, n_link, 3))
    cand = np.empty((8, 3))
    scratch = np.empty(3)
    stack = np.empty(max(1, nodes.shape[0]), dtype=np.int64)
    move = np.ones(n_link)
    for c in range(n_cfg):
        _segments(world[c], links, seg)
        _judge(seg, links, pairs, n_rr, kind, obstacles, axes, tree, nodes, order, pair_of, eps,
               margin, move, 0.0, out[c], cand, scratch, stack)
    return out


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
    return _verdicts(world, links, pairs, rr.shape[0], kind, obstacles, axes, tree, nodes, order,
                     pair_of, eps, margin)


@kernel
def check(qs: Array, joints: Array, zero: Array, links: Array, pairs: IndexArray, n_rr: int,
          kind: IndexArray, obstacles: Array, axes: Array, tree: Array, nodes: IndexArray,
          order: IndexArray, pair_of: IndexArray, eps: float, margin: float
          ) -> tuple[Array, VerdictArray]:
    """Link cylinder poses (N, L, 3, 4) and pair verdicts (N, P + Q) for configurations ``qs``
    (N, n) in one call, from the arrays :func:`pack` prepares once per collision world."""
    world = link_poses(qs, joints, zero, links)
    return world, _verdicts(world, links, pairs, n_rr, kind, obstacles, axes, tree, nodes, order,
                            pair_of, eps, margin)


@kernel
def summary(q: Array, joints: Array, zero: Array, links: Array, pairs: IndexArray, n_rr: int,
            kind: IndexArray, obstacles: Array, axes: Array, tree: Array, nodes: IndexArray,
            order: IndexArray, pair_of: IndexArray, eps: float, margin: float) -> int:
    """One configuration ``q`` (n,) in one call, nothing allocated for the caller: CLEAR when
    every pair is cleared, CONTACT when one is proven in contact, else UNDECIDED (then
    :func:`check` gives the poses and verdicts for the exact judge)."""
    n, n_link = q.shape[0], zero.shape[0]
    frames = np.empty((n + 1, 3, 4))
    world = np.empty((n_link, 3, 4))
    seg = np.empty((6, n_link, 3))
    row = np.zeros(pairs.shape[0], dtype=np.int8)
    stack = np.empty(max(1, nodes.shape[0]), dtype=np.int64)
    _poses_into(q, joints, zero, links, frames, world)
    _segments(world, links, seg)
    _judge(seg, links, pairs, n_rr, kind, obstacles, axes, tree, nodes, order, pair_of, eps,
           margin, np.ones(n_link), 0.0, row, np.empty((8, 3)), np.empty(3), stack)
    verdict = CLEAR
    for p in range(row.shape[0]):
        if row[p] == CONTACT:
            return CONTACT
        if row[p] == UNDECIDED:
            verdict = UNDECIDED
    return verdict


@kernel
def walk(a: Array, b: Array, steps: int, levers: Array, joints: Array, zero: Array,
         links: Array, pairs: IndexArray, n_rr: int, kind: IndexArray, obstacles: Array,
         axes: Array, tree: Array, nodes: IndexArray, order: IndexArray, pair_of: IndexArray,
         eps: float, margin: float) -> tuple[int, int, IndexArray, Array, VerdictArray]:
    """Walk the joint-space segment a -> b (n,) through its ``steps + 1`` evenly spaced
    configurations, skipping those that the clearance already proves free.

    At a configuration whose pairs are all cleared, each pair's clearance bound divided by how
    far the pair can close per step (its link's motion, or both links' for a link-link pair;
    ``levers`` (n, L): m per unit of joint j for the points of link cylinder k, see
    ``CollisionWorld.link_levers``) says how many next configurations cannot bring it into
    contact; the smallest over the pairs is skipped. Configurations with a pair left undecided
    are not skipped past.

    Returns:
        The index of the first configuration with a proven contact (-1: none), how many
        configurations were evaluated, and the undecided ones in order: their indices (U,),
        link poses (U, L, 3, 4) and verdicts (U, P + Q), for the exact judge.
    """
    n, n_link, n_pairs = a.shape[0], zero.shape[0], pairs.shape[0]
    move = np.zeros(n_link)  # per link, how far its points move per step (m)
    for k in range(n_link):
        for j in range(n):
            move[k] += levers[j, k] * abs(b[j] - a[j]) / steps
    motion = 0.0
    for k in range(n_link):
        motion = max(motion, move[k])
    q = np.empty(n)
    frames = np.empty((n + 1, 3, 4))
    world = np.empty((n_link, 3, 4))
    seg = np.empty((6, n_link, 3))
    cand = np.empty((8, 3))
    scratch = np.empty(3)
    stack = np.empty(max(1, nodes.shape[0]), dtype=np.int64)
    row = np.zeros(n_pairs, dtype=np.int8)
    where = np.empty(steps + 1, dtype=np.int64)
    poses = np.empty((steps + 1, n_link, 3, 4))
    verdicts = np.empty((steps + 1, n_pairs), dtype=np.int8)
    count = evaluated = 0
    k = 0
    while k <= steps:
        f = k / steps
        for j in range(n):
            q[j] = a[j] + (b[j] - a[j]) * f
        _poses_into(q, joints, zero, links, frames, world)
        _segments(world, links, seg)
        self_gap, scene_gap = _judge(seg, links, pairs, n_rr, kind, obstacles, axes, tree,
                                     nodes, order, pair_of, eps, margin, move, REFINE, row,
                                     cand, scratch, stack)
        evaluated += 1
        undecided = False
        for p in range(n_pairs):
            if row[p] == CONTACT:
                return k, evaluated, where[:count], poses[:count], verdicts[:count]
            if row[p] == UNDECIDED:
                undecided = True
        if undecided:
            where[count] = k
            poses[count] = world
            verdicts[count] = row
            count += 1
            k += 1
            continue
        if motion <= 0.0:
            break  # a == b: every configuration is this one
        free = min(scene_gap, self_gap)  # steps that cannot bring any pair into contact
        k += 1 + int(min(free * (1.0 - 1e-9), steps + 1.0))
    return -1, evaluated, where[:count], poses[:count], verdicts[:count]


Packed = tuple[Array, Array, Array, IndexArray, int, IndexArray, Array, Array, Array,
               IndexArray, IndexArray, IndexArray]


def pack(axes: Array, points: Array, revolute: IndexArray, zero: Array, radius: Array,
         half: Array, moved_by: IndexArray, rr: IndexArray, rs: IndexArray, kind: IndexArray,
         pose: Array, size: Array) -> Packed:
    """The arrays :func:`check` takes after ``qs`` (all but the tolerances), prepared once."""
    joints = np.ascontiguousarray(np.hstack([
        axes.reshape(-1, 3), points.reshape(-1, 3), np.asarray(revolute, float).reshape(-1, 1)]))
    links = prepare_links(np.ascontiguousarray(radius, dtype=float),
                          np.ascontiguousarray(half, dtype=float),
                          np.ascontiguousarray(moved_by, dtype=np.int64))
    pairs = np.ascontiguousarray(np.vstack([rr.reshape(-1, 2), rs.reshape(-1, 2)]),
                                 dtype=np.int64)
    kind = np.ascontiguousarray(kind, dtype=np.int64)
    obstacles, obstacle_axes = prepare_obstacles(kind, np.ascontiguousarray(pose, dtype=float),
                                                 np.ascontiguousarray(size, dtype=float))
    tree, nodes, order = scene_tree.build(obstacles[:, O_CENTRE:O_CENTRE + 3],
                                          obstacles[:, O_BOUND])
    pair_of = scene_tree.pair_table(rs, len(rr), len(radius), len(kind))
    return (joints, np.ascontiguousarray(zero, dtype=float), links, pairs, len(rr), kind,
            obstacles, obstacle_axes, tree, nodes, order, pair_of)


def warm_up() -> None:
    """Compile :func:`check` and :func:`walk` for the argument types the collision world
    passes (numba caches the machine code on disk, so later processes load it instead of
    compiling for ~20 s).
    Run once after installing (``make demo`` and ``make test`` do):
    ``python -c "from usar_arm.planning.bounds import warm_up; warm_up()"``."""
    eye = np.eye(4)
    packed = pack(np.array([[0.0, 0.0, 1.0]]), np.zeros((1, 3)), np.array([1]), eye[None],
                  np.array([0.1]), np.array([0.2]), np.array([1]), np.zeros((0, 2), np.int64),
                  np.array([[0, 0]], np.int64), np.array([BOX]), eye[None, :3, :],
                  np.array([[0.5, 0.5, 0.5]]))
    check(np.zeros((1, 1)), *packed, EPS, MARGIN)
    summary(np.zeros(1), *packed, EPS, MARGIN)
    walk(np.zeros(1), np.ones(1), 4, np.ones((1, 1)), *packed, EPS, MARGIN)
