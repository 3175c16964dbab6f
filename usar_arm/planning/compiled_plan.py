"""The compiled planner's Python side: one call of :func:`.plan_kernel.search` and one of
:func:`.plan_kernel.shortcut` for a plan, over the collision world's compiled verdicts.

The kernels take an edge only when the compiled walk proves every configuration of it apart at
the path check's density (a step at most ``options.resolution`` of joint motion and
``options.max_step`` m of any point's motion), so the path needs no repair; the caller
(:func:`.ptp.plan_to_joints`) checks it once more with the exact judge all the same, and plans
with OMPL's RRTConnect when this finds nothing within :data:`MAX_EDGES` edges.
"""

from __future__ import annotations

import math
import time

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning import bounds, plan_kernel
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ompl_adapter import (
    COMPILED,
    NARROW,
    WIDE_EDGES,
    OmplOptions,
    OmplResult,
    draw_seed,
)

__all__ = ["MAX_EDGES", "SHORTCUTS", "WIDE", "plan_compiled"]

WIDE = 0.2
"""The range of the wide phase as a fraction of the space's extent (OMPL's default range)."""
MAX_EDGES = 4000
"""Edges one compiled search may check before it gives up (and OMPL plans instead)."""
SHORTCUTS = 0
"""Random shortcuts tried after the greedy vertex reduction: none by default. With 40, paths
were no shorter in the robots stage's plans, and two of test_invariants' blended trajectories
(control.timing.blended) came out 3e-6 above the jerk limit at their 1 kHz finite-difference
check: waypoints a shortcut puts a hair's breadth from a vertex make segments that short."""


def plan_compiled(world: CollisionWorld, lower: Array, upper: Array, start: Array,
                  goal: Array, options: OmplOptions) -> OmplResult | None:
    """A path from ``start`` to ``goal`` found and shortened (when ``options.simplify``) in the
    compiled kernels, every edge proven free at the path check's density; None when the search
    ran out of edges, or at once when the bounding volumes leave the start or the goal
    undecided (near an obstacle: the walk cannot clear an edge from it). The seed is drawn
    from OMPL's generator (:func:`.ompl_adapter.draw_seed`), so :func:`.ompl_adapter.reseed`
    decides this plan as it decides OMPL's."""
    for end in (start, goal):  # (every edge from an end the walk cannot clear is blocked)
        if world.verdicts.summary(end)[0] != bounds.CLEAR:
            return None
    lower, upper = np.array(lower, float), np.array(upper, float)  # (writeable: as compiled)
    extent = float(np.linalg.norm(upper - lower))
    budget = (float(options.resolution), float(options.max_step), WIDE * extent,
              NARROW * extent, WIDE_EDGES, MAX_EDGES)
    arm, links = world.lever_arms(), world.link_levers()
    packed = world.verdicts.packed
    seed = draw_seed(options.seed)
    begin = time.perf_counter()
    path, edges, evaluated = plan_kernel.search(np.array(start, float), np.array(goal, float),
                                                lower, upper, arm, links, budget, seed, packed,
                                                bounds.EPS, bounds.MARGIN)
    searched = time.perf_counter() - begin
    if len(path) == 0:
        return None
    simplify = 0.0
    if options.simplify and len(path) > 2:
        begin = time.perf_counter()
        path = plan_kernel.shortcut(path, arm, links, float(options.resolution),
                                    float(options.max_step) if math.isfinite(options.max_step)
                                    else math.inf, SHORTCUTS, seed, packed, bounds.EPS,
                                    bounds.MARGIN)
        simplify = time.perf_counter() - begin
    path = np.array(path)
    path[0], path[-1] = start, goal
    return OmplResult(path, COMPILED, searched, simplify, int(evaluated), int(edges))
