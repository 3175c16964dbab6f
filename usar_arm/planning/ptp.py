"""PTP motions: a collision-free path in joint space to a configuration or to a tool0 pose."""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from usar_arm.core.errors import (
    GoalInCollisionError,
    NoPathError,
    OutOfLimitsError,
    StartInCollisionError,
)
from usar_arm.core.spatial import Array
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ik import IKSolver
from usar_arm.planning.ompl_adapter import (
    OmplOptions,
    OmplResult,
    edge_steps,
    plan_path,
)

log = logging.getLogger("usar_arm.planning")


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

    OMPL explores with edges checked every ``options.resolution`` of joint motion (fast, but a
    point far from the base can move a few centimetres between two checks). The path it returns
    is then checked so that no point of the robot moves more than ``options.max_step`` between
    checked configurations; a path that clips an obstacle between the planner's checks is
    planned again with every edge checked that densely.

    Raises:
        OutOfLimitsError, StartInCollisionError, GoalInCollisionError, NoPathError.
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

    result = plan_path(lower, upper, start, goal, state_valid, world.segment_free, options)
    blocked = _first_blocked(world, result.waypoints, options, levers)
    if blocked is None:
        return PtpPlan(result.waypoints, goal, result, time.perf_counter() - begin)
    log.info("the path clips an obstacle between the planner's checks on segment %d of %d; "
             "planning again with edges checked every %g m", blocked + 1,
             len(result.waypoints) - 1, options.max_step)
    result = plan_path(lower, upper, start, goal, state_valid, world.segment_free, options,
                       levers)
    blocked = _first_blocked(world, result.waypoints, options, levers)
    if blocked is not None:  # the planner checked every edge that densely: a planner defect
        raise NoPathError(options.planner, options.time_limit,
                          f"segment {blocked + 1} of the path is in collision")
    return PtpPlan(result.waypoints, goal, result, time.perf_counter() - begin, dense_replans=1)


def _first_blocked(world: CollisionWorld, waypoints: Array, options: OmplOptions,
                   levers: Array) -> int | None:
    """Index of the first segment of ``waypoints`` in collision when checked every
    ``options.resolution`` of joint motion and ``options.max_step`` m of robot motion."""
    for k in range(len(waypoints) - 1):
        a, b = waypoints[k], waypoints[k + 1]
        steps = edge_steps(a, b, options.resolution, levers, options.max_step)
        if not world.segment_free(a, b, steps):
            return k
    return None


def plan_to_pose(world: CollisionWorld, ik: IKSolver, start: Array, target: Array,
                 options: OmplOptions) -> PtpPlan:
    """A path to the best reachable IK solution of a tool0 pose (nearest the start first),
    trying the others when one cannot be reached.

    Raises:
        IKError (unreachable, limits, every solution in collision), StartInCollisionError,
        NoPathError (every solution tried).
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
                       plan.dense_replans)
    assert last is not None
    raise NoPathError(last.planner, last.time_limit_s,
                      f"none of the {len(result.solutions)} IK solution(s) could be reached")

