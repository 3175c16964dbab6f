"""PTP motions: a collision-free path in joint space to a configuration or to a tool0 pose."""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from usar_arm.errors import (
    GoalInCollisionError,
    NoPathError,
    OutOfLimitsError,
    StartInCollisionError,
)
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ik import IKSolver
from usar_arm.planning.ompl_adapter import (
    OmplOptions,
    OmplResult,
    edge_configurations,
    plan_path,
)
from usar_arm.spatial import Array

log = logging.getLogger("usar_arm.planning")


@dataclass(frozen=True)
class PtpPlan:
    """A joint-space path and how it was found."""

    waypoints: Array
    goal: Array
    ompl: OmplResult | None
    seconds: float
    goals_tried: int = 1


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

    Raises:
        OutOfLimitsError, StartInCollisionError, GoalInCollisionError, NoPathError.
    """
    begin = time.perf_counter()
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    check_state(world, names, lower, upper, start, "start")
    check_state(world, names, lower, upper, goal, "goal")
    if not np.any(world.in_collision_many(edge_configurations(start, goal, options.resolution))):
        return PtpPlan(np.vstack([start, goal]), goal, None, time.perf_counter() - begin)
    result = plan_path(lower, upper, start, goal, lambda q: not world.in_collision(q),
                       lambda qs: ~world.in_collision_many(qs), options)
    return PtpPlan(result.waypoints, goal, result, time.perf_counter() - begin)


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
        return PtpPlan(plan.waypoints, plan.goal, plan.ompl, time.perf_counter() - begin, k + 1)
    assert last is not None
    raise NoPathError(last.planner, last.time_limit,
                      f"none of the {len(result.solutions)} IK solution(s) could be reached")

