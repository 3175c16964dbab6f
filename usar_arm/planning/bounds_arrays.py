"""The plain arrays the compiled broadphase (:mod:`.bounds`) takes, prepared once per collision
world: the chain as joints (axis, point, revolute), each link cylinder's row (radius, half-length,
inner balls, bounding sphere, moving joints), each obstacle's row, the checked pairs and the
obstacles' sphere tree (:mod:`.scene_tree`); and the compiled forward kinematics of the link
cylinders over those arrays (product of exponentials, space frame, as :mod:`.poe`). Metres,
radians.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning import scene_tree
from usar_arm.planning.jit import kernel

IndexArray = np.ndarray[Any, np.dtype[np.int64]]
"""Integer arrays (pair indices, kinds)."""

BOX, SPHERE, CAPSULE, HULL = 0, 1, 2, 3
"""Obstacle kinds: an oriented box (half extents), a sphere (radius), a cylinder (radius,
half-length; its enclosing capsule clears pairs), and a triangle mesh's bounding box (it can
clear a pair but never proves a contact: python-fcl treats a mesh as a surface)."""

(RADIUS, HALF, RHO, REACH, BOUND, MOVED, OWNER, GROUP, GROUP_RADIUS, NEXT, COVER_FROM, COVER_TO,
 INNER_FROM, INNER_TO, SOLID) = range(15)
LINK_WIDTH = 15
"""Columns of the per-body array: the cylinder's radius and half-length (m), the radius of the
balls inside it and how far their centres reach from its centre along the axis, the radius of a
sphere around it, how many joints move it; the index of the link it belongs to (its bodies are
rigid together), and when every body of that link lies within ``GROUP_RADIUS`` (m) of one body's
axis segment, that body's index (``GROUP``; -1 otherwise): one capsule test then clears every
body pair of two such links at once, and one test clears a link's bodies against an obstacle;
``NEXT``: the group's next body after this one (the group's body first; -1 after the last);
``COVER_FROM``, ``COVER_TO``: the range of its ball groups (:mod:`.bounds_balls`; equal when it
has no ball cover); ``INNER_FROM``, ``INNER_TO``: the range, among the leaves, of the balls
inside a closed mesh (:mod:`.inner_balls`; equal when it has none); ``SOLID``: 1 when the body
is its cylinder (not a sphere, capsule, box or mesh inside it), so that balls at its rim prove
contacts (:func:`.gaps.rim_box_contact`), else 0."""

J_AXIS, J_POINT, J_REVOLUTE = 0, 3, 6
JOINT_WIDTH = 7
"""Columns of the per-joint array: the joint's unit axis (3) and a point on it (3) at the zero
configuration (space frame, m), then 1.0 for a revolute joint, 0.0 for a prismatic one."""

O_SIZE, O_START, O_DIR, O_IN_START, O_IN_DIR, O_RHO, O_BOUND, O_CENTRE, O_BOX = (
    0, 3, 6, 9, 12, 15, 16, 17, 20)
OBSTACLE_WIDTH = 23
"""Columns of the per-obstacle array: size (3), the enclosing segment's start and direction,
the inner balls' segment's start and direction, their radius, the radius of a sphere about the
centre that contains the obstacle, the centre (3), and the half extents (3) of the box about the
centre (along the obstacle's axes) that contains it: a cylinder's box clears what its capsule's
round ends cannot."""


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
        out[k, OWNER], out[k, GROUP], out[k, GROUP_RADIUS], out[k, NEXT] = k, -1.0, 0.0, -1.0
        out[k, COVER_FROM] = out[k, COVER_TO] = 0.0
        out[k, INNER_FROM] = out[k, INNER_TO] = 0.0
        out[k, SOLID] = 1.0
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
            out[s, O_BOX] = out[s, O_BOX + 1] = size[s, 0]
            out[s, O_BOX + 2] = size[s, 1]
        elif kind[s] == SPHERE:
            out[s, O_RHO] = size[s, 0]
            out[s, O_BOUND] = size[s, 0]
            out[s, O_BOX:O_BOX + 3] = size[s, 0]
        else:
            out[s, O_BOUND] = math.sqrt(size[s, 0] ** 2 + size[s, 1] ** 2 + size[s, 2] ** 2)
            out[s, O_BOX:O_BOX + 3] = size[s]
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
def poses_into(q: Array, joints: Array, zero: Array, links: Array, frames: Array,
                out: Array) -> None:
    """:func:`link_poses` of one configuration ``q`` (n,) into ``out`` (L, 3, 4), with
    ``frames`` (n + 1, 3, 4) as scratch: no allocation, for the hot loops."""
    n = q.shape[0]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
    t0 = t1 = t2 = 0.0
    frames[0] = 0.0
    frames[0, 0, 0] = frames[0, 1, 1] = frames[0, 2, 2] = 1.0
    for i in range(n):
        w0, w1, w2 = joints[i, J_AXIS], joints[i, J_AXIS + 1], joints[i, J_AXIS + 2]
        if joints[i, J_REVOLUTE] > 0.5:
            a = q[i]
            sn, co = math.sin(a), math.cos(a)
            v = 1.0 - co
            e00, e01, e02 = co + w0 * w0 * v, w0 * w1 * v - w2 * sn, w0 * w2 * v + w1 * sn
            e10, e11, e12 = w1 * w0 * v + w2 * sn, co + w1 * w1 * v, w1 * w2 * v - w0 * sn
            e20, e21, e22 = w2 * w0 * v - w1 * sn, w2 * w1 * v + w0 * sn, co + w2 * w2 * v
            p0, p1, p2 = joints[i, J_POINT], joints[i, J_POINT + 1], joints[i, J_POINT + 2]
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

    ``joints`` (n, JOINT_WIDTH): each joint's axis and a point on it at the zero configuration,
    then 1 for revolute or 0 for prismatic (columns ``J_AXIS``, ``J_POINT``, ``J_REVOLUTE``);
    ``zero`` (L, 4, 4) each body's pose at zero; ``links`` (L, LINK_WIDTH) with how many
    joints (a prefix of the chain) move each body at MOVED.
    """
    n_cfg, n = qs.shape
    out = np.empty((n_cfg, zero.shape[0], 3, 4))
    frames = np.empty((n + 1, 3, 4))  # rotation | position after the first i joints
    for c in range(n_cfg):
        poses_into(qs[c], joints, zero, links, frames, out[c])
    return out


class Packed(NamedTuple):
    """The arrays of a collision world as the kernels take them (:func:`pack` prepares them
    once per world; numba reads a named tuple's fields as cheaply as separate arguments)."""

    joints: Array
    """(n, JOINT_WIDTH): per joint, its axis, a point on it at zero, whether it is revolute."""
    zero: Array
    """(L, 4, 4): each body's pose at the zero configuration."""
    links: Array
    """(L, LINK_WIDTH): the per-body rows (columns ``RADIUS`` .. ``SOLID``)."""
    pairs: IndexArray
    """(P + Q, 2): the checked pairs, link-link (body, body) then link-obstacle (body, obstacle)."""
    n_rr: int
    """P: how many of ``pairs`` are link-link."""
    kind: IndexArray
    """(S,): the obstacles' kinds (``BOX``, ``SPHERE``, ``CAPSULE``, ``HULL``)."""
    obstacles: Array
    """(S, OBSTACLE_WIDTH): the per-obstacle rows (columns ``O_SIZE`` .. ``O_BOX``)."""
    axes: Array
    """(S, 3, 3): each obstacle's axes as rows."""
    tree: Array
    """(M, 4): the obstacles' sphere tree's nodes, centre and radius (:func:`.scene_tree.build`)."""
    nodes: IndexArray
    """(M, 4): the nodes' children and leaf ranges (:func:`.scene_tree.build`)."""
    order: IndexArray
    """(S,): the obstacles in the tree's leaf order."""
    pair_of: IndexArray
    """(L, S): the index of the pair of a body and an obstacle, -1 when it is not checked."""
    groups: Array
    """(G, 6): the mesh bodies' ball groups (:mod:`.bounds_balls`)."""
    leaves: Array
    """(M, 4): their leaves, then the balls inside closed meshes."""


Cover = tuple[Array, Array, Array]
"""A mesh body's balls: the groups (G, 6) and leaves (M, 4) of its
:class:`.ball_cover.BallCover`, and the balls inside it (K, 4) of :mod:`.inner_balls`."""


def pack_covers(covers: list[Cover | None]) -> tuple[IndexArray, Array, Array]:
    """Per body (L,), its balls (:data:`Cover`, or None) as one array each: the ranges of each
    body's groups and of its inner balls (L, 4), the groups (their leaf ranges shifted) and the
    leaves, every body's inner balls after all the cover leaves."""
    ranges = np.zeros((len(covers), 4), dtype=np.int64)
    groups, leaves, inner = [np.zeros((0, 6))], [np.zeros((0, 4))], [np.zeros((0, 4))]
    n_groups = n_leaves = 0
    for k, c in enumerate(covers):
        ranges[k, :2] = n_groups, n_groups
        if c is None:
            continue
        g = np.array(c[0], dtype=float)
        g[:, 4:6] += n_leaves
        groups.append(g)
        leaves.append(np.asarray(c[1], dtype=float))
        n_groups += len(g)
        n_leaves += len(c[1])
        ranges[k, 1] = n_groups
    for k, c in enumerate(covers):
        ranges[k, 2:] = n_leaves, n_leaves
        if c is not None:
            inner.append(np.asarray(c[2], dtype=float).reshape(-1, 4))
            n_leaves += len(inner[-1])
            ranges[k, 3] = n_leaves
    return ranges, np.ascontiguousarray(np.vstack(groups)), np.ascontiguousarray(
        np.vstack(leaves + inner))


def pack(axes: Array, points: Array, revolute: IndexArray, zero: Array, radius: Array,
         half: Array, moved_by: IndexArray, rr: IndexArray, rs: IndexArray, kind: IndexArray,
         pose: Array, size: Array,
         covers: list[Cover | None] | None = None) -> Packed:
    """The arrays :func:`check` takes after ``qs`` (all but the tolerances), prepared once;
    ``covers``: per body, its ball cover or None (see :func:`pack_covers`; default none)."""
    joints = np.ascontiguousarray(np.hstack([  # (columns J_AXIS, J_POINT, J_REVOLUTE)
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
    ranges, groups, leaves = pack_covers(covers if covers is not None else [None] * len(radius))
    links[:, COVER_FROM], links[:, COVER_TO] = ranges[:, 0], ranges[:, 1]
    links[:, INNER_FROM], links[:, INNER_TO] = ranges[:, 2], ranges[:, 3]
    return Packed(joints, np.ascontiguousarray(zero, dtype=float), links, pairs, len(rr), kind,
                  obstacles, obstacle_axes, tree, nodes, order, pair_of, groups, leaves)


def warm_up_world() -> tuple[Packed, Array]:
    """The smallest world the kernels take (one revolute joint, one body, one box) and its
    lever arms, read-only as a collision world hands them over: what the kernels' warm-ups
    compile against (numba keys its cache on the argument types, not the sizes)."""
    eye = np.eye(4)
    packed = pack(np.array([[0.0, 0.0, 1.0]]), np.zeros((1, 3)), np.array([1]), eye[None],
                  np.array([0.1]), np.array([0.2]), np.array([1]), np.zeros((0, 2), np.int64),
                  np.array([[0, 0]], np.int64), np.array([BOX]), eye[None, :3, :],
                  np.array([[0.5, 0.5, 0.5]]))
    levers = np.ones((1, 1))
    levers.setflags(write=False)
    return packed, levers
