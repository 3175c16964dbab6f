"""PTP motions: a collision-free path in joint space to a configuration or to a tool0 pose."""

from __future__ import annotations

import itertools
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from usar_arm.core.errors import (
    GoalInCollisionError,
    NoPathError,
    OutOfLimitsError,
    StartInCollisionError,
)
from usar_arm.core.spatial import Array
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.compiled_plan import MAX_EDGES, plan_compiled
from usar_arm.planning.ik import IKSolver
from usar_arm.planning.ompl_adapter import (
    COMPILED,
    FALLBACK,
    OmplOptions,
    OmplResult,
    edge_steps,
    plan_path,
)

log = logging.getLogger("usar_arm.planning")

MAX_REPAIRS = 3
"""Segments of one path replanned densely before the whole path is planned again so."""


@dataclass(frozen=True)
class PtpPlan:
    """A joint-space path and how it was found."""

    waypoints: Array
    goal: Array
    ompl: OmplResult | None
    seconds: float
    goals_tried: int = 1
    dense_replans: int = 0
    """1 when the first path clipped an obstacle between checks and was planned again."""
    repaired: int = 0
    """Segments of the planner's path that clipped an obstacle between its checks and were
    replaced by a path planned between their ends with every edge checked densely."""


def check_state(world: CollisionWorld, names: tuple[str, ...], lower: Array, upper: Array,
                q: Array, what: str) -> None:
    """Raise the typed error when ``q`` is outside the limits or in collision."""
    for i, name in enumerate(names):
        if not lower[i] - 1e-9 <= q[i] <= upper[i] + 1e-9:
            raise OutOfLimitsError(what, name, float(q[i]), float(lower[i]), float(upper[i]))
    if world.in_collision(q):
        pairs = world.contacts(q)
        raise (StartInCollisionError if what == "start" else GoalInCollisionError)(pairs)


def plan_to_joints(world: CollisionWorld, names: tuple[str, ...], lower: Array, upper: Array,
                   start: Array, goal: Array, options: OmplOptions) -> PtpPlan:
    """A path from ``start`` to the configuration ``goal``.

    With :data:`.ompl_adapter.COMPILED` (the default planner), the compiled planner
    (:mod:`.compiled_plan`) searches and shortens a path every edge of which is free at this
    module's path-check density by proof: the compiled walk's bounding volumes, which contain
    the exact shapes, clear every configuration of it (an undecided end's escape segment, by
    python-fcl); so it is not checked again (the check would only repeat those proofs, and
    the benchmark's mesh judge verifies every path). OMPL's RRTConnect plans when the compiled
    search finds nothing.

    OMPL explores with edges checked every ``options.resolution`` of joint motion (fast, but a
    point far from the base can move a few centimetres between two checks). The path it returns
    is then checked so that no point of the robot moves more than ``options.max_step`` between
    checked configurations; a segment that clips an obstacle between the planner's checks is
    replaced by a path planned between its ends with every edge checked that densely, and when
    that fails (at most :data:`MAX_REPAIRS` segments, within ``options.time_limit`` of the
    call's start), the whole path is planned again so.

    Raises:
        OutOfLimitsError: the start or goal outside the joint limits.
        StartInCollisionError: the start in collision.
        GoalInCollisionError: the goal in collision.
        NoPathError: no path within the time limit.
    """
    begin = time.perf_counter()
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    check_state(world, names, lower, upper, start, "start")
    check_state(world, names, lower, upper, goal, "goal")
    levers = world.lever_arms()
    if _first_blocked(world, np.vstack([start, goal]), options, levers) is None:
        return PtpPlan(np.vstack([start, goal]), goal, None, time.perf_counter() - begin)

    def state_valid(q: Array) -> bool:
        return not world.in_collision(q)

    if options.planner == COMPILED:
        found = plan_compiled(world, lower, upper, start, goal, options)
        spent = time.perf_counter() - begin
        if spent > options.time_limit:  # (the kernel cannot read the clock: its budget is edges)
            raise NoPathError(COMPILED, options.time_limit,
                              f"the compiled search took {spent:.3g} s"
                              + ("" if found is None else " (a path found too late)"))
        options = replace(options, planner=FALLBACK)
        if found is not None:  # (free at this module's density: see the docstring)
            return PtpPlan(found.waypoints, goal, found, time.perf_counter() - begin)
        log.info("the compiled planner found no path (within %d edges, or an end only "
                 "python-fcl can clear); planning with OMPL's RRTConnect", MAX_EDGES)
        options = replace(options, time_limit=options.time_limit - spent)
    result = plan_path(lower, upper, start, goal, state_valid, world.segment_free, options)
    path, repaired = _repaired(world, lower, upper, result.waypoints, state_valid, options,
                               levers, begin + options.time_limit)
    if path is not None:
        return PtpPlan(path, goal, result, time.perf_counter() - begin, repaired=repaired)
    log.info("a segment of the path clips an obstacle between the planner's checks and could "
             "not be repaired; planning again with every edge checked every %g m",
             options.max_step)
    result = plan_path(lower, upper, start, goal, state_valid, world.segment_free, options,
                       levers)
    blocked = _first_blocked(world, result.waypoints, options, levers)
    if blocked is not None:  # the planner checked every edge that densely: a planner defect
        raise NoPathError(options.planner, options.time_limit,
                          f"segment {blocked + 1} of the path is in collision")
    return PtpPlan(result.waypoints, goal, result, time.perf_counter() - begin, dense_replans=1)


def _repaired(world: CollisionWorld, lower: Array, upper: Array, waypoints: Array,
              state_valid: Callable[[Array], bool], options: OmplOptions, levers: Array,
              deadline: float) -> tuple[Array | None, int]:
    """``waypoints`` checked every ``options.resolution`` of joint motion and
    ``options.max_step`` m of robot motion, each segment that is not free replaced by a path
    planned between its ends with every edge checked that densely (so free as checked); and
    how many were replaced. None when a segment could not be replaced before ``deadline``
    (``time.perf_counter()`` s) or more than :data:`MAX_REPAIRS` were needed."""
    path, repaired = [waypoints[0]], 0
    for a, b in itertools.pairwise(waypoints):
        if _dense_free(world, a, b, options, levers):
            path.append(b)
            continue
        left = deadline - time.perf_counter()
        if repaired == MAX_REPAIRS or left <= 0:
            return None, repaired
        try:
            sub = plan_path(lower, upper, a, b, state_valid, world.segment_free,
                            replace(options, time_limit=left), levers)
        except NoPathError:
            return None, repaired
        blocked = _first_blocked(world, sub.waypoints, options, levers)
        if blocked is not None:  # every edge was checked that densely: a planner defect
            raise NoPathError(options.planner, options.time_limit,
                              f"segment {blocked + 1} of a repair is in collision")
        path.extend(sub.waypoints[1:])
        repaired += 1
    return np.array(path), repaired


def _first_blocked(world: CollisionWorld, waypoints: Array, options: OmplOptions,
                   levers: Array) -> int | None:
    """Index of the first segment of ``waypoints`` in collision when checked every
    ``options.resolution`` of joint motion and ``options.max_step`` m of robot motion."""
    for k, (a, b) in enumerate(itertools.pairwise(waypoints)):
        if not _dense_free(world, a, b, options, levers):
            return k
    return None


def _dense_free(world: CollisionWorld, a: Array, b: Array, options: OmplOptions,
                levers: Array) -> bool:
    """True when the segment a -> b is free, checked every ``options.resolution`` of joint
    motion and ``options.max_step`` m of robot motion (the path check of this module)."""
    return world.segment_free(a, b, edge_steps(a, b, options.resolution, levers,
                                               options.max_step))


def plan_to_pose(world: CollisionWorld, ik: IKSolver, start: Array, target: Array,
                 options: OmplOptions) -> PtpPlan:
    """A path to the best reachable IK solution of a tool0 pose (nearest the start first),
    trying the others when one cannot be reached.

    Raises:
        IKError: unreachable, beyond the limits, or every solution in collision.
        StartInCollisionError: the start in collision.
        NoPathError: no path to any solution tried.
    """
    begin = time.perf_counter()
    start = np.asarray(start, float)
    check_state(world, ik.names, ik.lower, ik.upper, start, "start")
    result = ik.solve(target, start, all_solutions=True, collision=world)
    last: NoPathError | None = None
    for k, sol in enumerate(result.solutions):
        try:
            plan = plan_to_joints(world, ik.names, ik.lower, ik.upper, start, np.array(sol.q),
                                  options)
        except NoPathError as exc:
            log.info("no path to IK solution %d of %d; trying the next", k + 1,
                     len(result.solutions))
            last = exc
            continue
        return PtpPlan(plan.waypoints, plan.goal, plan.ompl, time.perf_counter() - begin, k + 1,
                       plan.dense_replans, plan.repaired)
    assert last is not None
    raise NoPathError(last.planner, last.time_limit_s,
                      f"none of the {len(result.solutions)} IK solution(s) could be reached")

