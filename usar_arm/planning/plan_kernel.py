"""The compiled planner: RRT-Connect and shortcutting over the compiled verdicts, in one call
each, with no Python between two edges.

Every edge is the compiled walk of :mod:`.bounds_walk` at the path check's density (a step at
most ``resolution`` of joint motion and ``max_step`` m of any point's motion, as
:func:`.ompl_adapter.edge_steps`), and an edge is taken only when the walk proves every one of
its configurations apart (CLEAR): a configuration the bounding volumes leave undecided counts as
blocked here, never handed to python-fcl. So a path found is free as densely as
:func:`.ptp.plan_to_joints` checks paths, by proofs about the exact shapes, and the caller
takes it as it is (it does not check it again), falling back to OMPL's planner when the
compiled search finds nothing within its edge budget (a passage only python-fcl can clear, or
a hard problem).

RRT-Connect as OMPL's (:class:`ompl.geometric.RRTConnect`): two trees, from the start and the
goal, a uniform sample, the tree that grew last extended towards it by at most the range, the
other tree connected to the new configuration edge by edge; nearest neighbours by the Euclidean
joint distance (a linear scan: the trees stay small); the range ``wide`` for the first
``wide_edges`` edges, then ``narrow`` (two phases, as :func:`.ompl_adapter._solve`'s; the
caller's :data:`.compiled_plan.WIDE` and :data:`.compiled_plan.NARROW`). The random numbers are
numba's generator seeded with the plan's seed, so a plan depends on its seed alone.

Shortcutting (:func:`shortcut`): from each kept waypoint, the farthest later waypoint it sees
directly (greedy vertex reduction), then random shortcuts between two points on the path.
"""

from __future__ import annotations

import math

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning.bounds_arrays import Packed
from usar_arm.planning.bounds_walk import DONE, EVALUATED, walk
from usar_arm.planning.jit import inline_kernel, kernel

__all__ = ["Budget", "edge_clear", "search", "shortcut", "warm_up"]

Budget = tuple[float, float, float, float, int, int]
"""What a compiled plan may spend and how densely it checks: ``resolution`` (rad or m per
step), ``max_step`` (m of any point's motion per step), the wide and narrow ranges (rad or m),
how many edges the wide phase may check, how many edges in all."""


@inline_kernel
def _steps(a: Array, b: Array, arm_levers: Array, resolution: float, max_step: float) -> int:
    """:func:`.ompl_adapter.edge_steps` in the kernel: steps of at most ``resolution`` per joint
    and ``max_step`` m of motion (``arm_levers`` (n,): m per unit of each joint)."""
    largest, moved = 0.0, 0.0
    for j in range(a.shape[0]):
        d = abs(b[j] - a[j])
        largest = max(largest, d)
        moved += arm_levers[j] * d
    steps = max(1, math.ceil(largest / resolution))
    if math.isfinite(max_step):
        steps = max(steps, math.ceil(moved / max_step))
    return steps


@kernel
def edge_clear(a: Array, b: Array, arm_levers: Array, link_levers: Array, resolution: float,
               max_step: float, packed: Packed, eps: float, margin: float,
               evaluated: np.ndarray) -> bool:
    """True when the compiled walk proves every configuration of a -> b apart, checked every
    ``resolution`` of joint motion and ``max_step`` m of any point's motion (an undecided
    configuration counts as blocked). ``link_levers`` (n, L): the walk's lever arms;
    ``evaluated`` (1,) int64: the configurations the walk evaluated are added to it."""
    steps = _steps(a, b, arm_levers, resolution, max_step)
    proven = np.full(steps + 1, -1, dtype=np.int64)
    queue = np.empty((2 * steps + 4, 2), dtype=np.int64)
    control = np.zeros(4, dtype=np.int64)
    poses = np.empty((1, packed.zero.shape[0], 3, 4))
    rows = np.empty((1, packed.pairs.shape[0]), dtype=np.int8)
    code, count = walk(a, b, steps, link_levers, proven, queue, control, 1, poses, rows,
                       packed, eps, margin)
    evaluated[0] += control[EVALUATED]
    return code == DONE and count == 0


@inline_kernel
def _nearest(tree: Array, size: int, q: Array) -> int:
    """The index of the node of ``tree`` (its first ``size`` rows) nearest ``q``."""
    best, best_d = 0, math.inf
    for k in range(size):
        d = 0.0
        for j in range(q.shape[0]):
            e = tree[k, j] - q[j]
            d += e * e
        if d < best_d:
            best, best_d = k, d
    return best


@inline_kernel
def _steer(frm: Array, to: Array, reach: float, out: Array) -> bool:
    """``out``: ``to``, or the point ``reach`` from ``frm`` towards it when farther; True when
    ``to`` itself."""
    d = 0.0
    for j in range(frm.shape[0]):
        d += (to[j] - frm[j]) ** 2
    d = math.sqrt(d)
    if d <= reach:
        out[:] = to
        return True
    for j in range(frm.shape[0]):
        out[j] = frm[j] + (to[j] - frm[j]) * (reach / d)
    return False


@kernel
def search(start: Array, goal: Array, lower: Array, upper: Array, arm_levers: Array,
           link_levers: Array, budget: Budget, seed: int, packed: Packed, eps: float,
           margin: float) -> tuple[Array, int, int]:
    """An RRT-Connect path (k, n) from ``start`` to ``goal`` whose every edge the compiled walk
    proves free (see the module's notes), how many edges it checked and how many
    configurations their walks evaluated; an empty path (0, n)
    when the edge budget ran out first. ``budget``: :data:`Budget`."""
    resolution, max_step, wide, narrow, wide_edges, max_edges = budget
    np.random.seed(seed)
    n = start.shape[0]
    capacity = max_edges + 2
    nodes = np.empty((2, capacity, n))
    parent = np.full((2, capacity), -1, dtype=np.int64)
    size = np.ones(2, dtype=np.int64)
    nodes[0, 0], nodes[1, 0] = start, goal
    sample, new = np.empty(n), np.empty(n)
    evaluated = np.zeros(1, dtype=np.int64)
    edges, grow = 0, 0
    while edges < max_edges:
        reach = wide if edges < wide_edges else narrow
        for j in range(n):
            sample[j] = lower[j] + (upper[j] - lower[j]) * np.random.random()
        near = _nearest(nodes[grow], size[grow], sample)
        _steer(nodes[grow, near], sample, reach, new)
        edges += 1
        if not edge_clear(nodes[grow, near], new, arm_levers, link_levers, resolution,
                          max_step, packed, eps, margin, evaluated):
            grow = 1 - grow
            continue
        added = size[grow]
        nodes[grow, added], parent[grow, added] = new, near
        size[grow] += 1
        other = 1 - grow
        while edges < max_edges:  # connect the other tree to the new configuration
            near = _nearest(nodes[other], size[other], nodes[grow, added])
            reached = _steer(nodes[other, near], nodes[grow, added], reach, new)
            edges += 1
            if not edge_clear(nodes[other, near], new, arm_levers, link_levers, resolution,
                              max_step, packed, eps, margin, evaluated):
                break
            tip = size[other]
            nodes[other, tip], parent[other, tip] = new, near
            size[other] += 1
            if reached:
                return _joined(nodes, parent, grow, added, tip), edges, int(evaluated[0])
        grow = other
    return np.empty((0, n)), edges, int(evaluated[0])


@inline_kernel
def _joined(nodes: Array, parent: np.ndarray, grow: int, added: int, tip: int) -> Array:
    """The path from the start's tree (0) through the two meeting nodes to the goal's (1):
    ``added`` of tree ``grow`` and ``tip`` of the other, the same configuration (once)."""
    first, second = (added, tip) if grow == 0 else (tip, added)
    head = _depth(parent, 0, first)
    path = np.empty((head + _depth(parent, 1, parent[1, second]), nodes.shape[2]))
    k, at = first, head - 1
    while k >= 0:
        path[at] = nodes[0, k]
        at, k = at - 1, parent[0, k]
    k, at = parent[1, second], head
    while k >= 0:
        path[at] = nodes[1, k]
        at, k = at + 1, parent[1, k]
    return path


@inline_kernel
def _depth(parent: np.ndarray, tree: int, k: int) -> int:
    """How many nodes from node ``k`` of ``tree`` to its root, both included (0 for -1)."""
    count = 0
    while k >= 0:
        count, k = count + 1, parent[tree, k]
    return count


@kernel
def shortcut(path: Array, arm_levers: Array, link_levers: Array, resolution: float,
             max_step: float, attempts: int, seed: int, packed: Packed, eps: float,
             margin: float) -> Array:
    """``path`` (k, n) shortened: each kept waypoint joined to the farthest later waypoint it
    sees by an edge the compiled walk proves free, then ``attempts`` random shortcuts between
    two points of the path (the same proof); the ends kept."""
    np.random.seed(seed)
    k, n = path.shape
    evaluated = np.zeros(1, dtype=np.int64)
    kept = np.empty((k, n))
    kept[0] = path[0]
    count, i = 1, 0
    while i < k - 1:
        j = k - 1
        while j > i + 1 and not edge_clear(path[i], path[j], arm_levers, link_levers,
                                           resolution, max_step, packed, eps, margin, evaluated):
            j -= 1
        kept[count] = path[j]
        count += 1
        i = j
    current = kept[:count].copy()
    a, b = np.empty(n), np.empty(n)
    for _ in range(attempts):
        m = current.shape[0]
        if m < 3:
            break
        s, t = np.random.randint(0, m - 1), np.random.randint(0, m - 1)
        if abs(s - t) < 1:
            continue
        s, t = min(s, t), max(s, t)
        u, v = np.random.random(), np.random.random()
        a[:] = current[s] + (current[s + 1] - current[s]) * u
        b[:] = current[t] + (current[t + 1] - current[t]) * v
        if not edge_clear(a, b, arm_levers, link_levers, resolution, max_step, packed, eps,
                          margin, evaluated):
            continue
        out = np.empty((s + 1 + 2 + m - t - 1, n))
        out[:s + 1] = current[:s + 1]
        out[s + 1], out[s + 2] = a, b
        out[s + 3:] = current[t + 1:]
        current = out
    return current


def warm_up() -> None:
    """Compile :func:`search` and :func:`shortcut` for the argument types the planner passes
    (numba caches the machine code on disk; see :mod:`.compiled`)."""
    from usar_arm.planning.bounds import EPS, MARGIN
    from usar_arm.planning.bounds_arrays import warm_up_world

    packed, levers = warm_up_world()
    arm = np.ones(1)
    arm.setflags(write=False)
    budget = (0.01, 0.005, 1.0, 0.2, 30, 100)
    search(np.zeros(1), np.ones(1), -np.ones(1), np.ones(1) * 2, arm, levers, budget,
                     0, packed, EPS, MARGIN)
    shortcut(np.array([[0.0], [0.5], [1.0]]), arm, levers, 0.01, 0.005, 4, 0, packed, EPS,
             MARGIN)
