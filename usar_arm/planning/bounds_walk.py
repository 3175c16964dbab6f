"""The compiled segment check: a joint-space segment's configurations checked coarse to fine, each
evaluated configuration proving free the ones within its clearance on both sides.

A segment a -> b of ``steps`` steps has the configurations k = 0 .. steps (at a + (b - a) k /
steps). Its two ends are evaluated first, then the middle of every run of configurations that
the evaluated ones leave unproven, breadth first (the middle, the quarters...): a blocked
segment ends at one of its first evaluations, wherever the block lies, and a free one needs
only the evaluations whose proven runs cover it. At a configuration whose pairs are all
cleared, each pair's clearance bound divided by how far the pair can close per step
(:func:`.bounds.judge_pairs`) is how many steps, forwards and backwards alike, cannot bring it into
contact; the smallest over the pairs is that configuration's proven run.

How far a body's points can move per step is bounded twice, and the smaller bound is taken,
joint by joint (:func:`motion_here`): by the global lever arms (``levers``: per joint, the
farthest any point of the body can be from its axis, over every configuration), and by the
lever arms at this configuration, which hold for ``H`` steps from it: the body's distance from
each joint's axis here, plus the body's own extent, plus how far the joints after that one can
move the body towards or away from the axis in ``H`` steps (their global lever arms); over the
``H`` steps that adds half of it on average. ``H`` is the distance to the far end of the run
being filled, and a proven run is never longer than ``H``; so the scene judge is capped there
(it skips the obstacles and refinements that could only prove more).

An undecided configuration (a pair the bounding volumes can neither clear nor prove in contact)
proves nothing around it; :func:`walk` hands it over with its poses and verdicts for the exact
judge (the first at once, then in batches of 2, 4...), and the caller calls it again to go on
from where it stopped (:func:`segment_free`), so the exact judge too sees the segment coarse to
fine, and a contact only it can confirm ends the check early.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning.bounds import (
    REFINE,
    VerdictArray,
    axis_segments,
    ball_scratch_kernel,
    judge_pairs,
)
from usar_arm.planning.bounds_arrays import (
    BOUND,
    J_AXIS,
    J_POINT,
    J_REVOLUTE,
    MOVED,
    IndexArray,
    Packed,
    poses_into,
)
from usar_arm.planning.bounds_scene import CONTACT, UNDECIDED
from usar_arm.planning.jit import inline_kernel, kernel

__all__ = ["DONE", "FOUND", "MORE", "segment_free", "walk"]

DONE = 0
"""The segment is done: every configuration is proven free, or undecided and handed over."""
FOUND = 1
"""A configuration is proven in contact."""
MORE = 2
"""As many undecided configurations as asked for are handed over; the segment goes on."""
HEAD, TAIL, EVALUATED, STARTED = range(4)
"""Entries of the walk's control array: where its queue of runs starts and ends, how many
configurations it evaluated, and whether its ends were queued."""


@inline_kernel
def segment_levers(a: Array, b: Array, steps: int, levers: Array, links: Array
                   ) -> tuple[Array, Array, Array, float]:
    """What the walk of a -> b bounds its motions with: each joint's change per step (n,)
    (rad or m); per body k, how far joints 0 .. j - 1 can move its points per step by the
    global lever arms (L, n + 1) (m); per joint j and body k, how fast the joints after j can
    move the body towards or away from j's axis (n, L) (m per step); and the largest motion of
    any body per step (m; 0 when a == b)."""
    n, n_link = a.shape[0], links.shape[0]
    per_step = np.empty(n)
    for j in range(n):
        per_step[j] = abs(b[j] - a[j]) / steps
    global_cum = np.zeros((n_link, n + 1))
    growth = np.zeros((n, n_link))
    motion = 0.0
    for k in range(n_link):
        for j in range(n):
            global_cum[k, j + 1] = global_cum[k, j] + levers[j, k] * per_step[j]
        motion = max(motion, global_cum[k, n])
        for j in range(n):
            for i in range(j + 1, int(links[k, MOVED])):
                growth[j, k] += levers[i, k] * per_step[i]
    return per_step, global_cum, growth, motion


@inline_kernel
def motion_here(seg: Array, frames: Array, joints: Array, links: Array, per_step: Array,
                growth: Array, horizon: float, global_cum: Array, cum: Array, move: Array
                ) -> None:
    """Per body k, how far joints 0 .. j - 1 can move its points per step within ``horizon``
    steps of this configuration, into ``cum`` (L, n + 1) and ``move`` (L,) (as
    :func:`.bounds.judge_pairs` reads them; m per step): per joint, the smaller of the global bound
    (``global_cum``'s increments) and the body centre's distance from the joint's axis here
    (``seg[5]``, ``frames`` (n + 1, 3, 4) of :func:`.bounds_arrays.poses_into`) plus the body's
    extent (``BOUND``) plus ``growth[j, k]`` (m per step) times half the horizon, times the
    joint's change per step ``per_step[j]`` (rad). A prismatic joint keeps its global bound."""
    n, n_link = per_step.shape[0], links.shape[0]
    for j in range(n):  # (joint by joint: its axis is placed once for every body)
        revolute = joints[j, J_REVOLUTE] > 0.5
        f = frames[j]
        w0, w1, w2 = joints[j, J_AXIS], joints[j, J_AXIS + 1], joints[j, J_AXIS + 2]
        p0, p1, p2 = joints[j, J_POINT], joints[j, J_POINT + 1], joints[j, J_POINT + 2]
        u0 = f[0, 0] * w0 + f[0, 1] * w1 + f[0, 2] * w2
        u1 = f[1, 0] * w0 + f[1, 1] * w1 + f[1, 2] * w2
        u2 = f[2, 0] * w0 + f[2, 1] * w1 + f[2, 2] * w2
        x0 = f[0, 0] * p0 + f[0, 1] * p1 + f[0, 2] * p2 + f[0, 3]
        x1 = f[1, 0] * p0 + f[1, 1] * p1 + f[1, 2] * p2 + f[1, 3]
        x2 = f[2, 0] * p0 + f[2, 1] * p1 + f[2, 2] * p2 + f[2, 3]
        for k in range(n_link):
            bound = global_cum[k, j + 1] - global_cum[k, j]
            if revolute and j < int(links[k, MOVED]) and bound > 0.0:
                v0, v1, v2 = seg[5, k, 0] - x0, seg[5, k, 1] - x1, seg[5, k, 2] - x2
                along = v0 * u0 + v1 * u1 + v2 * u2
                off_axis = math.sqrt(max(0.0, v0 * v0 + v1 * v1 + v2 * v2 - along * along))
                here = per_step[j] * (off_axis * (1.0 + 1e-12) + links[k, BOUND] + 1e-12
                                      + growth[j, k] * horizon * 0.5)
                bound = min(bound, here)
            cum[k, j + 1] = cum[k, j] + bound
    for k in range(n_link):
        move[k] = cum[k, n]


@kernel
def walk(a: Array, b: Array, steps: int, levers: Array, proven: IndexArray, queue: IndexArray,
         control: IndexArray, batch: int, poses: Array, rows: VerdictArray, packed: Packed,
         eps: float, margin: float) -> tuple[int, int]:
    """Check the configurations of the segment a -> b (n,) coarse to fine until one is proven
    in contact (FOUND), ``batch`` of them are undecided (MORE) or the segment is done (DONE);
    and how many undecided configurations this call found, in order, their link poses in
    ``poses`` (U, L, 3, 4) and pair verdicts in ``rows`` (U, P + Q) (U >= batch).

    The state is the caller's, so that a call goes on from where the last one stopped:
    ``proven`` (steps + 1,) int64, -1 at first: per evaluated configuration, how many steps
    on each side its clearance proves free (0 when undecided); ``queue`` (2 steps + 4, 2) int64:
    runs to fill, as the evaluated configurations that bound them (-1 and -2: the segment's
    start and end); ``control`` (4,) int64, zeros at first (see ``HEAD`` .. ``STARTED``).
    ``levers`` (n, L): the global lever arms (m per unit of joint j for body k); ``packed``:
    the collision world's arrays (:class:`.bounds_arrays.Packed`)."""
    joints, zero, links = packed.joints, packed.zero, packed.links
    n, n_link = a.shape[0], zero.shape[0]
    per_step, global_cum, growth, motion = segment_levers(a, b, steps, levers, links)
    move, cum = np.zeros(n_link), np.zeros((n_link, n + 1))
    q, frames = np.empty(n), np.empty((n + 1, 3, 4))
    seg, cand, scratch = np.empty((6, n_link, 3)), np.empty((8, 3)), np.empty(3)
    stack = np.empty(max(1, packed.nodes.shape[0]), dtype=np.int64)
    balls = ball_scratch_kernel(links, packed.groups, packed.leaves)
    world, row = np.empty((n_link, 3, 4)), np.zeros(packed.pairs.shape[0], dtype=np.int8)
    head, tail, count = control[HEAD], control[TAIL], 0
    if control[STARTED] == 0:
        control[STARTED] = 1
        queue[0, 0], queue[0, 1] = -1, 0
        tail = 1
        if motion > 0.0:  # (a == b: every configuration is the first)
            queue[1, 0], queue[1, 1] = -2, steps
            tail = 2
    while head < tail:
        left, right = queue[head, 0], queue[head, 1]
        head += 1
        if left < 0:  # an end of the segment
            k, horizon = right, steps
        else:
            lo, hi = left + proven[left] + 1, right - proven[right] - 1
            if lo > hi:
                continue
            k = (lo + hi) // 2
            horizon = max(k - lo, hi - k) + 1
        for j in range(n):
            q[j] = a[j] + (b[j] - a[j]) * (k / steps)
        poses_into(q, joints, zero, links, frames, world)
        axis_segments(world, links, seg)
        motion_here(seg, frames, joints, links, per_step, growth, float(horizon),
                    global_cum, cum, move)
        self_gap, scene_gap = judge_pairs(seg, world, packed, eps, margin, move, cum, REFINE,
                                          horizon + 1.0, row, cand, scratch, stack, balls)
        control[EVALUATED] += 1
        undecided = False
        for p in range(row.shape[0]):
            if row[p] == CONTACT:
                control[HEAD], control[TAIL] = head, tail
                return FOUND, count
            undecided = undecided or row[p] == UNDECIDED
        free = min(scene_gap, self_gap) * (1.0 - 1e-9)
        proven[k] = 0 if undecided else min(int(min(free, steps + 1.0)), horizon)
        if left == -2:  # both ends are known: the segment between them
            queue[tail, 0], queue[tail, 1] = 0, steps
            tail += 1
        elif left >= 0:
            queue[tail, 0], queue[tail, 1] = left, k
            queue[tail + 1, 0], queue[tail + 1, 1] = k, right
            tail += 2
        if undecided:
            poses[count], rows[count] = world, row
            count += 1
            if count == batch:
                control[HEAD], control[TAIL] = head, tail
                return MORE, count
    control[HEAD], control[TAIL] = head, tail
    return DONE, count


def segment_free(a: Array, b: Array, steps: int, levers: Array, packed: Packed,
                 eps: float, margin: float, in_contact: Callable[[Array, VerdictArray], bool]
                 ) -> tuple[bool, int]:
    """Whether every configuration of a -> b (``steps`` + 1 of them) is free, and how many the
    walk evaluated: :func:`walk` to the end, ``in_contact(world, row)`` (the exact judge)
    deciding the undecided configurations in the walk's order, stopping at the first in
    contact; the walk hands them over in batches of 1, 2, 4... (a call costs a few
    microseconds: one per configuration would cost more than most of them). ``packed``: the
    arrays of :func:`.bounds.pack` (as the collision world keeps them)."""
    proven = np.full(steps + 1, -1, dtype=np.int64)
    queue = np.empty((2 * steps + 4, 2), dtype=np.int64)
    control = np.zeros(4, dtype=np.int64)
    poses = np.empty((steps + 1, packed.zero.shape[0], 3, 4))
    rows = np.empty((steps + 1, packed.pairs.shape[0]), dtype=np.int8)
    batch = 1
    while True:
        code, count = walk(a, b, steps, levers, proven, queue, control, batch, poses, rows,
                           packed, eps, margin)
        if code == FOUND:
            return False, int(control[EVALUATED])
        for u in range(count):
            if in_contact(poses[u], rows[u]):
                return False, int(control[EVALUATED])
        if code == DONE:
            return True, int(control[EVALUATED])
        batch *= 2


def warm_up() -> None:
    """Compile :func:`walk` for the argument types the collision world passes (numba caches
    the machine code on disk; see :mod:`.compiled`)."""
    from usar_arm.planning.bounds import EPS, MARGIN
    from usar_arm.planning.bounds_arrays import warm_up_world

    packed, levers = warm_up_world()
    segment_free(np.zeros(1), np.ones(1), 4, levers, packed, EPS, MARGIN, lambda w, r: True)
