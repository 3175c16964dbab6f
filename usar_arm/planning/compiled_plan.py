"""The compiled planner's Python side: one call of :func:`.plan_kernel.search` and one of
:func:`.plan_kernel.shortcut` for a plan, over the collision world's compiled verdicts.

The kernels take an edge only when the compiled walk proves every configuration of it apart at
the path check's density (a step at most ``options.resolution`` of joint motion and
``options.max_step`` m of any point's motion), so the path needs no repair and the caller
(:func:`.ptp.plan_to_joints`) does not check it again; it plans with OMPL's RRTConnect when
this finds nothing within :data:`MAX_EDGES` edges.

An end the bounding volumes leave undecided (a grasp close to an object: no edge from it can be
proven free by them) is left by an *escape*: a configuration nearby that they clear, reached
from the end by a straight segment the exact judge (python-fcl on what they leave undecided)
finds free at the path check's density (:func:`escape`). The compiled search then plans
between the escapes, and the path is the end, the escape, the search's path, the other escape,
the other end.
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
    WIDE_EDGES,
    OmplOptions,
    OmplResult,
    draw_seed,
    edge_steps,
)

__all__ = ["ESCAPE_RADII", "ESCAPE_TRIES", "MAX_EDGES", "NARROW", "SHORTCUTS", "WIDE", "escape",
           "plan_compiled"]

WIDE = 0.2
"""The range of the wide phase (its first :data:`.ompl_adapter.WIDE_EDGES` edges) as a
fraction of the space's extent: OMPL's default range. In an A/B on the bench's problems a
wider one (up to the whole extent) took about a third off the KR60's median and added about
two thirds to the UR5's; this one is kept."""
NARROW = 0.1
"""The range after the wide phase, as a fraction of the space's extent. OMPL's second phase
takes :data:`.ompl_adapter.NARROW` (0.04); in the same A/B this one shortened every robot's
tail (the KR60's p90 and mean, and fewer UR5 and Panda plans left to OMPL), the medians
unchanged within the noise."""
MAX_EDGES = 4000
"""Edges one compiled search may check before it gives up (and OMPL plans instead)."""
SHORTCUTS = 0
"""Random shortcuts tried after the greedy vertex reduction: none by default. With 40, paths
were no shorter in the robots stage's plans, and two of test_invariants' blended trajectories
(control.timing.blended) came out 3e-6 above the jerk limit at their 1 kHz finite-difference
check: waypoints a shortcut puts a hair's breadth from a vertex make segments that short."""


ESCAPE_RADII = (0.05, 0.1, 0.2, 0.4)
"""How far (the joint-space distance, rad or m) from an undecided end an escape is looked for,
nearest first."""
ESCAPE_TRIES = 8
"""Random directions tried at each radius, after the direction of the other end."""


def escape(world: CollisionWorld, end: Array, towards: Array, lower: Array, upper: Array,
           options: OmplOptions, rng: np.random.Generator) -> Array | None:
    """A configuration within :data:`ESCAPE_RADII` of ``end`` (inside the limits) that the
    bounding volumes clear, the straight segment to it from ``end`` free by the exact judge at
    the path check's density (``options.resolution`` of joint motion, ``options.max_step`` m
    of robot motion); tried towards ``towards`` first, then in random directions. None when
    no such configuration was found."""
    levers = world.lever_arms()
    ahead = towards - end
    length = float(np.linalg.norm(ahead))
    for radius in ESCAPE_RADII:
        directions = rng.normal(size=(ESCAPE_TRIES, len(end)))
        if length > 0:
            directions = np.vstack([ahead / length, directions])
        for d in directions:
            q = np.clip(end + radius * d / max(float(np.linalg.norm(d)), 1e-12), lower, upper)
            if world.verdicts.summary(q)[0] != bounds.CLEAR:
                continue
            if world.segment_free(end, q, edge_steps(end, q, options.resolution, levers,
                                                     options.max_step)):
                return q
    return None


def plan_compiled(world: CollisionWorld, lower: Array, upper: Array, start: Array,
                  goal: Array, options: OmplOptions) -> OmplResult | None:
    """A path from ``start`` to ``goal`` found and shortened (when ``options.simplify``) in the
    compiled kernels, every edge proven free at the path check's density (an undecided end's
    edge to its :func:`escape` by the exact judge); None when the search ran out of edges or an
    undecided end has no escape. The seed is drawn from OMPL's generator
    (:func:`.ompl_adapter.draw_seed`), so :func:`.ompl_adapter.reseed` decides this plan as it
    decides OMPL's."""
    start, goal = np.array(start, float), np.array(goal, float)
    lower, upper = np.array(lower, float), np.array(upper, float)  # (writeable: as compiled)
    seed = draw_seed(options.seed)
    begin = time.perf_counter()
    rng = np.random.default_rng(seed)
    inner = []
    for end, other in ((start, goal), (goal, start)):
        if world.verdicts.summary(end)[0] == bounds.CLEAR:
            inner.append(end)
            continue
        out = escape(world, end, other, lower, upper, options, rng)
        if out is None:  # (every edge from it the walk cannot clear is blocked)
            return None
        inner.append(out)
    extent = float(np.linalg.norm(upper - lower))
    budget = (float(options.resolution), float(options.max_step), WIDE * extent,
              NARROW * extent, WIDE_EDGES, MAX_EDGES)
    arm, links = world.lever_arms(), world.link_levers()
    packed = world.verdicts.packed
    path, edges, evaluated = plan_kernel.search(inner[0], inner[1], lower, upper, arm, links,
                                                budget, seed, packed, bounds.EPS, bounds.MARGIN)
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
    path[0], path[-1] = inner
    head = [start] if inner[0] is not start else []
    tail = [goal] if inner[1] is not goal else []
    path = np.vstack([*head, path, *tail])
    return OmplResult(path, COMPILED, searched, simplify, int(evaluated), int(edges))
