"""One body of the compiled broadphase (:mod:`.bounds`) against one obstacle: a lower bound of
their clearance, and the proof of a contact; and the span of a link's group of bodies. Inline
kernels (:mod:`.jit`): compiled into the scene verdicts' loop, no call per pair. Metres.
"""

from __future__ import annotations

import math

from usar_arm.core.spatial import Array
from usar_arm.planning.bounds_arrays import (
    BOUND,
    BOX,
    GROUP,
    GROUP_RADIUS,
    HALF,
    HULL,
    O_BOUND,
    O_CENTRE,
    O_DIR,
    O_IN_DIR,
    O_IN_START,
    O_RHO,
    O_SIZE,
    O_START,
    RADIUS,
    REACH,
    RHO,
)
from usar_arm.planning.gaps import (
    cylinder_box_gap,
    inner_box_contact,
    point_box_distance,
    segment_distance,
)
from usar_arm.planning.jit import inline_kernel


@inline_kernel
def group_span(links: Array, g: int, move: Array) -> tuple[int, int, float, float, float]:
    """The bodies judged with body ``g`` (first and last index: ``g`` alone, or the contiguous
    bodies whose ``GROUP`` is ``g``), how far their points move (the largest of ``move``), and
    the radius, and the radius of a sphere around, of the cylinder along ``g``'s axis that
    holds them all (m)."""
    lo = hi = g
    move_g, radius_g, bound_g = move[g], links[g, RADIUS], links[g, BOUND]
    if int(links[g, GROUP]) == g:
        while lo > 0 and int(links[lo - 1, GROUP]) == g:
            lo -= 1
        while hi + 1 < links.shape[0] and int(links[hi + 1, GROUP]) == g:
            hi += 1
        for m in range(lo, hi + 1):
            move_g = max(move_g, move[m])
        radius_g = links[g, GROUP_RADIUS]
        bound_g = math.sqrt(radius_g * radius_g + links[g, HALF] * links[g, HALF])
    return lo, hi, move_g, radius_g, bound_g


@inline_kernel
def cylinder_obstacle_gap(centre: Array, axis: Array, start: Array, direction: Array,
                          radius: float, half: float, bound: float, o: Array, kind: int,
                          axes: Array, refine: float, cand: Array) -> float:
    """A lower bound of the clearance (m) between a cylinder (``centre``, unit ``axis``, its
    axis segment ``start`` + [0, 1] ``direction``, ``radius``, ``half``-length, ``bound`` the
    radius of a sphere around it) and obstacle row ``o`` of ``kind`` with rows ``axes``: the
    quick one (the centre against the solid box, or two bounding spheres), and when that is
    below ``refine``, the tighter one too (the exact cylinder against the box's separating
    axes, or the enclosing capsules)."""
    if kind == BOX or kind == HULL:
        # the centre against the solid box: tighter than two spheres for large flat boxes
        gap = (point_box_distance(centre, o[O_START:O_START + 3], axes, o[O_SIZE:O_SIZE + 3])
               - bound)
        if gap <= refine:
            gap = max(gap, cylinder_box_gap(centre, axis, radius, half, o[O_START:O_START + 3],
                                            axes, o[O_SIZE:O_SIZE + 3], cand))
        return gap
    gap = (math.sqrt((centre[0] - o[O_CENTRE]) ** 2 + (centre[1] - o[O_CENTRE + 1]) ** 2
                     + (centre[2] - o[O_CENTRE + 2]) ** 2) - bound - o[O_BOUND])
    if gap <= refine:
        gap = max(gap, segment_distance(start, direction, o[O_START:O_START + 3],
                                        o[O_DIR:O_DIR + 3]) - radius - o[O_SIZE])
    return gap


@inline_kernel
def body_contact(seg: Array, links: Array, i: int, o: Array, kind: int, axes: Array,
                 margin: float, scratch: Array) -> bool:
    """Whether body ``i`` (its segments ``seg``, row ``links[i]``) provably overlaps obstacle
    row ``o`` by more than ``margin`` (m): balls inside both overlap. Never for a mesh's hull
    (python-fcl sees a mesh as a surface)."""
    if kind == BOX:
        return inner_box_contact(seg[5, i], seg[4, i], links[i, RHO], links[i, REACH],
                                 o[O_START:O_START + 3], axes, o[O_SIZE:O_SIZE + 3], margin,
                                 scratch)
    if kind == HULL:
        return False
    inner = segment_distance(seg[2, i], seg[3, i], o[O_IN_START:O_IN_START + 3],
                             o[O_IN_DIR:O_IN_DIR + 3])
    return bool(inner < links[i, RHO] + o[O_RHO] - margin)
