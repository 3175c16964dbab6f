"""The scene side of the compiled broadphase (:mod:`.bounds`): a configuration's verdicts on the
link-obstacle pairs, walked down the obstacles' sphere tree (:mod:`.scene_tree`), with the
clearance bounds a walk along a segment skips by. Metres.

A body is a cylinder (axis segment, radius, half-length); an obstacle a box (or a mesh's bounding
box: HULL), a sphere or a capsule, as :func:`.bounds_arrays.prepare_obstacles` lays them out.

:func:`judge_scene` walks the tree (``tree``, ``nodes``, ``order`` of :func:`.scene_tree.build`,
``pair_of`` of :func:`.scene_tree.pair_table`; ``stack`` scratch of at least M entries): each
link visits only the subtrees its bounding sphere comes within the current bound (or ``eps``)
of, a link that does not move (``move`` 0, as every link of a single configuration) only those
within ``eps``: what matters for it is whether a pair is cleared, not by how much. The bound
starts at ``cap`` units of motion (a walk's horizon: it proves no more), so the subtrees
beyond it are skipped too. The pairs below the others stay CLEAR. A pair is first bounded by
its centre against the solid box (or by two spheres); when that is below ``refine`` units of
its link's motion (at least ``eps`` m) and below the bound found so far (else it cannot
lower it), by the exact cylinder against the box (or the capsules' axes) too. The
per-pair tests are written out in the loop, not called through inlined helpers: a kernel call
per pair costs more than the test itself. They read the obstacle's row, the body's centre and
the ball centres by index (the :mod:`.gaps` functions that take coordinates): an array view
(``obstacles[s]``, a slice) costs a reference count to make and one to drop, about as much as
the test it feeds.

A link whose bodies form a group (``GROUP``, ``NEXT``) walks the tree once, with the cylinder
around them all (the group body's axis, ``GROUP_RADIUS``); an obstacle that this cylinder clears
is cleared for every body of the link, else each body is tested as its own. The bodies of one
link are checked against the same obstacles (pairs are disabled link by link:
:meth:`.verdicts.CompiledVerdicts.check_pairs` makes sure).
"""

from __future__ import annotations

import math

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning import bounds_balls
from usar_arm.planning.bounds_arrays import (
    BOUND,
    BOX,
    CAPSULE,
    GROUP,
    GROUP_RADIUS,
    HALF,
    HULL,
    INNER_FROM,
    INNER_TO,
    NEXT,
    O_BOUND,
    O_BOX,
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
    SOLID,
    IndexArray,
)
from usar_arm.planning.gaps import (
    cylinder_box_gap,
    inner_box_contact,
    point_box_distance,
    point_segment_distance,
    rim_box_contact,
    rim_cylinders_contact,
    segment_distance,
    xyz_box_distance,
)
from usar_arm.planning.jit import inline_kernel

CLEAR, CONTACT, UNDECIDED = 0, 1, 2
"""Verdicts on a pair: provably apart, provably touching (by more than the margin), or for the
exact judge to decide."""


@inline_kernel
def _group_motion(links: Array, move: Array, i: int) -> float:
    """The largest motion (as ``move``) of the bodies of the group body ``i`` leads."""
    motion = move[i]
    b = int(links[i, NEXT])
    while b >= 0:
        motion = max(motion, move[b])
        b = int(links[b, NEXT])
    return motion


@inline_kernel
def _beyond(seg: Array, i: int, radius: float, spheres: Array, s: int, centre: int, bound: int,
            scene_gap: float, move: float, eps: float) -> bool:
    """The sphere of ``radius`` (m) about body ``i``'s centre and the sphere of row ``s`` of
    ``spheres`` (centre in columns ``centre`` .. + 2, radius in column ``bound``: a subtree's
    or an obstacle's) are apart by more than ``eps`` and than ``scene_gap`` units of the body's
    ``move`` (a moving body): nothing inside them can lower the gap found so far."""
    gap = (math.sqrt((seg[5, i, 0] - spheres[s, centre]) ** 2
                     + (seg[5, i, 1] - spheres[s, centre + 1]) ** 2
                     + (seg[5, i, 2] - spheres[s, centre + 2]) ** 2)
           - spheres[s, bound] - radius)
    return gap > (max(scene_gap * move, eps) if move > 0.0 else eps)


@inline_kernel
def judge_scene(seg: Array, world: Array, links: Array, kind: IndexArray, obstacles: Array,
                axes: Array, tree: Array, nodes: IndexArray, order: IndexArray,
                pair_of: IndexArray, groups: Array, leaves: Array, eps: float, margin: float,
                move: Array, refine: float, cap: float, out: np.ndarray, cand: Array,
                scratch: Array, stack: IndexArray, balls: tuple[Array, Array, np.ndarray]
                ) -> float:
    """Verdicts on the link-obstacle pairs into ``out``, and the smallest cleared gap per unit
    of the link's motion ``move`` (0 when a pair is not cleared; at most ``cap``). See the
    module's notes."""
    scene_gap = cap
    for i in range(pair_of.shape[0]):
        if links[i, GROUP] >= 0 and links[i, GROUP] != i:
            continue  # tested with its group's first body
        grouped = links[i, GROUP] == i
        radius_g = links[i, GROUP_RADIUS] if grouped else links[i, RADIUS]
        bound_g = math.sqrt(links[i, HALF] ** 2 + radius_g ** 2) if grouped else links[i, BOUND]
        move_g = _group_motion(links, move, i) if grouped else move[i]
        stack[0], top = 0, 1
        while top > 0:
            top -= 1
            nd = stack[top]
            if _beyond(seg, i, bound_g, tree, nd, 0, 3, scene_gap, move_g, eps):
                continue  # every pair below is cleared, and farther apart than any bound found
            if nodes[nd, 0] >= 0:
                stack[top], stack[top + 1] = nodes[nd, 0], nodes[nd, 1]
                top += 2
                continue
            for k in range(nodes[nd, 2], nodes[nd, 3]):
                s = order[k]
                if pair_of[i, s] < 0 or _beyond(seg, i, bound_g, obstacles, s, O_CENTRE,
                                                O_BOUND, scene_gap, move_g, eps):
                    continue  # (not checked; or apart as a subtree is)
                # First the group's cylinder (when grouped), then each body b from the first.
                whole = grouped
                b = i
                while b >= 0:
                    if whole:
                        radius, bounding, mv = radius_g, bound_g, move_g
                    else:
                        radius, bounding, mv = links[b, RADIUS], links[b, BOUND], move[b]
                    near = max(eps, min(refine, scene_gap) * mv) if mv > 0.0 else eps
                    if kind[s] == BOX or kind[s] == HULL:  # the centre against the solid box
                        gap = xyz_box_distance(
                            seg[5, b, 0], seg[5, b, 1], seg[5, b, 2], obstacles[s, O_START],
                            obstacles[s, O_START + 1], obstacles[s, O_START + 2], axes[s],
                            obstacles[s, O_SIZE], obstacles[s, O_SIZE + 1],
                            obstacles[s, O_SIZE + 2]) - bounding
                        if gap <= near:
                            o = obstacles[s]
                            gap = max(gap, cylinder_box_gap(
                                seg[5, b], seg[4, b], radius, links[b, HALF],
                                o[O_START:O_START + 3], axes[s], o[O_SIZE:O_SIZE + 3], cand))
                    else:
                        gap = (math.sqrt((seg[5, b, 0] - obstacles[s, O_CENTRE]) ** 2
                                         + (seg[5, b, 1] - obstacles[s, O_CENTRE + 1]) ** 2
                                         + (seg[5, b, 2] - obstacles[s, O_CENTRE + 2]) ** 2)
                               - bounding - obstacles[s, O_BOUND])
                        if gap <= near:
                            o = obstacles[s]
                            gap = max(gap, segment_distance(
                                seg[0, b], seg[1, b], o[O_START:O_START + 3],
                                o[O_DIR:O_DIR + 3]) - radius - o[O_SIZE])
                            if gap <= near and kind[s] == CAPSULE:  # the box about the cylinder
                                gap = max(gap, cylinder_box_gap(
                                    seg[5, b], seg[4, b], radius, links[b, HALF],
                                    o[O_CENTRE:O_CENTRE + 3], axes[s], o[O_BOX:O_BOX + 3],
                                    cand))
                    if gap > eps:
                        if mv > 0.0:
                            scene_gap = min(scene_gap, gap / mv)
                        b = int(links[b, NEXT]) if grouped and not whole else -1
                    elif whole:
                        whole = False  # each body on its own, from the first (b == i)
                    else:  # a mesh body's balls have a look, else FCL decides
                        scene_gap = _second_look(seg, world, links, groups, leaves, b, kind[s],
                                                 obstacles[s], axes[s], eps, margin, mv,
                                                 scene_gap, out, pair_of[b, s], scratch, balls)
                        b = int(links[b, NEXT]) if grouped else -1
    return scene_gap


@inline_kernel
def _second_look(seg: Array, world: Array, links: Array, groups: Array, leaves: Array, b: int,
                 kind: int, o: Array, axes: Array, eps: float, margin: float, mv: float,
                 scene_gap: float, out: np.ndarray, p: int, scratch: Array,
                 balls: tuple[Array, Array, np.ndarray]) -> float:
    """A pair body ``b``'s cylinder left undecided: cleared by a mesh body's balls, else proven
    in contact (:func:`_touching`) or left to FCL (verdict into ``out[p]``). Returns the scene
    gap per unit of motion (:func:`judge_scene`'s), updated."""
    gap = bounds_balls.body_obstacle_gap(b, kind, o, axes, world, links, groups, leaves, eps,
                                         balls)
    if gap > eps:
        return min(scene_gap, gap / mv) if mv > 0.0 else scene_gap
    out[p] = CONTACT if _touching(seg, world, links, leaves, b, kind, o, axes, margin,
                                  scratch) else UNDECIDED
    return 0.0


@inline_kernel
def _touching(seg: Array, world: Array, links: Array, leaves: Array, b: int, kind: int,
              o: Array, axes: Array, margin: float, scratch: Array) -> bool:
    """Body ``b`` and the obstacle are proven in contact: balls inside both overlap by more
    than ``margin`` (for a mesh, see :func:`_inside_mesh`; never for a mesh's box or a
    cylinder that only bounds its body): the balls on the body's axis, then at its rim
    (:func:`.gaps.rim_box_contact`, :func:`.gaps.rim_cylinders_contact`)."""
    if links[b, INNER_TO] > links[b, INNER_FROM]:
        return _inside_mesh(seg, world, links, leaves, b, kind, o, axes, margin, scratch)
    if kind == HULL or links[b, RHO] <= 0.0:  # a mesh's box; a cylinder that only bounds
        return False
    c, z, r, h = seg[5, b], seg[4, b], links[b, RADIUS], links[b, HALF]
    rims = links[b, SOLID] > 0.5  # (a sphere's or a capsule's cylinder has no rim of its own)
    if kind == BOX:
        return bool(inner_box_contact(c, z, links[b, RHO], links[b, REACH],
                                      o[O_START:O_START + 3], axes, o[O_SIZE:O_SIZE + 3], margin,
                                      scratch)
                    or (rims and rim_box_contact(c, z, r, h, o[O_START:O_START + 3], axes,
                                                 o[O_SIZE:O_SIZE + 3], margin, scratch)))
    if segment_distance(seg[2, b], seg[3, b], o[O_IN_START:O_IN_START + 3],
                        o[O_IN_DIR:O_IN_DIR + 3]) < links[b, RHO] + o[O_RHO] - margin:
        return True
    return kind == CAPSULE and rims and bool(rim_cylinders_contact(
        c, z, r, h, o[O_CENTRE:O_CENTRE + 3], axes[2], o[O_SIZE], o[O_SIZE + 1], margin,
        scratch))


@inline_kernel
def _inside_mesh(seg: Array, world: Array, links: Array, leaves: Array, b: int, kind: int,
                 o: Array, axes: Array, margin: float, x: Array) -> bool:
    """A closed mesh body ``b`` and a solid obstacle are proven in contact: one of the mesh's
    inner balls (:mod:`.inner_balls`, rows ``INNER_FROM:INNER_TO`` of ``leaves``) reaches more
    than ``margin`` into the obstacle, and the obstacle reaches more than ``margin`` out of the
    sphere that holds the mesh (``BOUND`` about the cylinder's centre). The obstacle then holds a
    point inside the mesh and one outside, so the mesh's surface crosses it. A box is the
    obstacle itself; a sphere or cylinder is seen through the balls inside it."""
    if kind == HULL:
        return False
    c = seg[5, b]
    if kind == BOX:
        far = 0.0
        for a in range(3):
            d = ((o[O_START] - c[0]) * axes[a, 0] + (o[O_START + 1] - c[1]) * axes[a, 1]
                 + (o[O_START + 2] - c[2]) * axes[a, 2])
            far += (abs(d) + o[O_SIZE + a]) ** 2
        far = math.sqrt(far)
    else:
        p, u = o[O_IN_START:O_IN_START + 3], o[O_IN_DIR:O_IN_DIR + 3]
        far = max(math.sqrt((p[0] - c[0]) ** 2 + (p[1] - c[1]) ** 2 + (p[2] - c[2]) ** 2),
                  math.sqrt((p[0] + u[0] - c[0]) ** 2 + (p[1] + u[1] - c[1]) ** 2
                            + (p[2] + u[2] - c[2]) ** 2)) + o[O_RHO]
    if far <= links[b, BOUND] + margin:
        return False
    t = world[b]
    for m in range(int(links[b, INNER_FROM]), int(links[b, INNER_TO])):
        for a in range(3):
            x[a] = (t[a, 0] * leaves[m, 0] + t[a, 1] * leaves[m, 1] + t[a, 2] * leaves[m, 2]
                    + t[a, 3])
        if kind == BOX:
            reach = point_box_distance(x, o[O_START:O_START + 3], axes, o[O_SIZE:O_SIZE + 3])
        else:
            reach = point_segment_distance(x, o[O_IN_START:O_IN_START + 3],
                                           o[O_IN_DIR:O_IN_DIR + 3]) - o[O_RHO]
        if reach < leaves[m, 3] - margin:
            return True
    return False
