"""The second look of the compiled broadphase (:mod:`.bounds`) at a pair its cylinders leave
undecided: the balls that cover a mesh body's surface (:mod:`.ball_cover`), group balls first,
then their leaves. A pair is cleared when every ball of its mesh bodies is apart from the other
body (its balls, or the capsule around its cylinder; an obstacle's solid box, sphere or capsule),
with the same margin ``eps`` as the cylinders. Metres.

Each gap is a lower bound of the distance between the mesh's surface and the other body (every
point of the surface is in a leaf, and every leaf in its group), so a walk skips by it as by a
cylinder's. ``links`` carries each body's range of groups (``COVER_FROM``, ``COVER_TO``; equal
when it has none); ``groups`` (G, 6) and ``leaves`` (M, 4) are in the body's cylinder frame and
are placed in the world (``wg`` (G, 3), ``wl`` (M, 3)) once per configuration: a body's group
balls when it is first looked at, a group's leaves only when the group does not clear the pair
on its own (``placed`` (L + G,): flags per body, then per group; zeroed per configuration by the
caller).
"""

from __future__ import annotations

import math

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning.bounds_arrays import (
    BOX,
    COVER_FROM,
    COVER_TO,
    HULL,
    O_DIR,
    O_SIZE,
    O_START,
    RADIUS,
)
from usar_arm.planning.gaps import xyz_box_distance, xyz_segment_distance
from usar_arm.planning.jit import inline_kernel


@inline_kernel
def has_balls(links: Array, b: int) -> bool:
    """Body ``b`` has a ball cover."""
    return links[b, COVER_TO] > links[b, COVER_FROM]


@inline_kernel
def place(world: Array, links: Array, groups: Array, leaves: Array, b: int, wg: Array,
          wl: Array, placed: np.ndarray) -> None:
    """Body ``b``'s group balls at its pose ``world[b]`` (3, 4), once per configuration (its
    leaves wait for :func:`place_leaves`: most groups clear the pair on their own)."""
    if placed[b]:
        return
    placed[b] = 1
    t = world[b]
    for g in range(int(links[b, COVER_FROM]), int(links[b, COVER_TO])):
        for a in range(3):
            wg[g, a] = t[a, 0] * groups[g, 0] + t[a, 1] * groups[g, 1] + t[a, 2] * groups[g, 2] \
                + t[a, 3]


@inline_kernel
def place_leaves(world: Array, links: Array, groups: Array, leaves: Array, b: int, g: int,
                 wl: Array, placed: np.ndarray) -> None:
    """The leaves of body ``b``'s group ``g`` at its pose, once per configuration (their flag:
    ``placed[L + g]``)."""
    flag = links.shape[0] + g
    if placed[flag]:
        return
    placed[flag] = 1
    t = world[b]
    for m in range(int(groups[g, 4]), int(groups[g, 5])):
        for a in range(3):
            wl[m, a] = (t[a, 0] * leaves[m, 0] + t[a, 1] * leaves[m, 1]
                        + t[a, 2] * leaves[m, 2] + t[a, 3])


@inline_kernel
def _apart(p: Array, i: int, q: Array, j: int) -> float:
    """Distance (m) between the points ``p[i]`` and ``q[j]`` (read by index: no views)."""
    return math.sqrt((p[i, 0] - q[j, 0]) ** 2 + (p[i, 1] - q[j, 1]) ** 2
                     + (p[i, 2] - q[j, 2]) ** 2)


@inline_kernel
def _to_axis(w: Array, g: int, seg: Array, j: int) -> float:
    """Distance (m) from the point ``w[g]`` to body ``j``'s axis segment (``seg`` as
    :func:`.bounds.axis_segments`)."""
    return xyz_segment_distance(w[g, 0], w[g, 1], w[g, 2], seg[0, j, 0], seg[0, j, 1],
                                seg[0, j, 2], seg[1, j, 0], seg[1, j, 1], seg[1, j, 2])


@inline_kernel
def bodies_gap(i: int, j: int, seg: Array, world: Array, links: Array, groups: Array,
               leaves: Array, eps: float, balls: tuple[Array, Array, np.ndarray]) -> float:
    """:func:`pair_gap` of bodies ``i`` and ``j`` from the side of one that has balls,
    placing them (``balls``: ``wg``, ``wl``, ``placed``); -inf when neither has any."""
    wg, wl, placed = balls
    if not has_balls(links, i):
        if not has_balls(links, j):
            return -math.inf
        i, j = j, i
    place(world, links, groups, leaves, i, wg, wl, placed)
    if has_balls(links, j):
        place(world, links, groups, leaves, j, wg, wl, placed)
    return pair_gap(i, j, seg, world, links, groups, leaves, wg, wl, placed, eps)


@inline_kernel
def body_obstacle_gap(b: int, kind: int, o: Array, axes: Array, world: Array, links: Array,
                      groups: Array, leaves: Array, eps: float,
                      balls: tuple[Array, Array, np.ndarray]) -> float:
    """:func:`obstacle_gap` of body ``b``, placing it; -inf when it has no balls."""
    if not has_balls(links, b):
        return -math.inf
    wg, wl, placed = balls
    place(world, links, groups, leaves, b, wg, wl, placed)
    return obstacle_gap(b, kind, o, axes, world, links, groups, leaves, wg, wl, placed, eps)


@inline_kernel
def pair_gap(i: int, j: int, seg: Array, world: Array, links: Array, groups: Array,
             leaves: Array, wg: Array, wl: Array, placed: np.ndarray, eps: float) -> float:
    """A lower bound (m) of the distance between body ``i``'s covered surface and body ``j``
    (its balls when it has some, else the capsule around its cylinder; ``seg`` as
    :func:`.bounds.axis_segments`), both placed; at most ``eps`` as soon as a pair of balls is."""
    best = math.inf
    j_balls = has_balls(links, j)
    r_j = links[j, RADIUS]
    for g in range(int(links[i, COVER_FROM]), int(links[i, COVER_TO])):
        gap = _to_axis(wg, g, seg, j) - groups[g, 3] - r_j
        if gap > eps:
            best = min(best, gap)
            continue
        place_leaves(world, links, groups, leaves, i, g, wl, placed)
        if not j_balls:
            for m in range(int(groups[g, 4]), int(groups[g, 5])):
                gap = _to_axis(wl, m, seg, j) - leaves[m, 3] - r_j
                if gap <= eps:
                    return gap
                best = min(best, gap)
            continue
        for h in range(int(links[j, COVER_FROM]), int(links[j, COVER_TO])):
            gap = _apart(wg, g, wg, h) - groups[g, 3] - groups[h, 3]
            if gap > eps:
                best = min(best, gap)
                continue
            place_leaves(world, links, groups, leaves, j, h, wl, placed)
            for m in range(int(groups[g, 4]), int(groups[g, 5])):
                gap = _apart(wl, m, wg, h) - leaves[m, 3] - groups[h, 3]
                if gap > eps:
                    best = min(best, gap)
                    continue
                for n in range(int(groups[h, 4]), int(groups[h, 5])):
                    gap = _apart(wl, m, wl, n) - leaves[m, 3] - leaves[n, 3]
                    if gap <= eps:
                        return gap
                    best = min(best, gap)
    return best


@inline_kernel
def _to_obstacle(w: Array, g: int, kind: int, o: Array, axes: Array) -> float:
    """Distance (m) from the point ``w[g]`` to the obstacle (row ``o`` of
    :func:`.bounds_arrays.prepare_obstacles`): its solid box (a mesh's: its bounding box), or
    the capsule around it (a sphere's is the sphere)."""
    if kind == BOX or kind == HULL:
        return xyz_box_distance(w[g, 0], w[g, 1], w[g, 2], o[O_START], o[O_START + 1],
                                o[O_START + 2], axes, o[O_SIZE], o[O_SIZE + 1], o[O_SIZE + 2])
    return xyz_segment_distance(w[g, 0], w[g, 1], w[g, 2], o[O_START], o[O_START + 1],
                                o[O_START + 2], o[O_DIR], o[O_DIR + 1],
                                o[O_DIR + 2]) - o[O_SIZE]


@inline_kernel
def obstacle_gap(b: int, kind: int, o: Array, axes: Array, world: Array, links: Array,
                 groups: Array, leaves: Array, wg: Array, wl: Array, placed: np.ndarray,
                 eps: float) -> float:
    """A lower bound (m) of the distance between body ``b``'s covered surface (placed) and an
    obstacle (see :func:`_to_obstacle`); at most ``eps`` as soon as a leaf is."""
    best = math.inf
    for g in range(int(links[b, COVER_FROM]), int(links[b, COVER_TO])):
        gap = _to_obstacle(wg, g, kind, o, axes) - groups[g, 3]
        if gap > eps:
            best = min(best, gap)
            continue
        place_leaves(world, links, groups, leaves, b, g, wl, placed)
        for m in range(int(groups[g, 4]), int(groups[g, 5])):
            gap = _to_obstacle(wl, m, kind, o, axes) - leaves[m, 3]
            if gap <= eps:
                return gap
            best = min(best, gap)
    return best
