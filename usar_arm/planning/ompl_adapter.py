"""Joint-space path planning with OMPL (the ``ompl`` 2.x wheels, nanobind bindings).

States are checked one by one; edges by a Python motion validator that answers, in one call
per edge, whether every configuration along it at a stated resolution is free (the collision
world walks the edge and skips the configurations its clearance proves free). OMPL's RNG is
process-global and can only be seeded before the first sample (an OMPL 2.x limitation): the
first plan of a process seeds it, so a process's sequence of plans is reproducible.

This is the only module that imports ``ompl``.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from usar_arm.core.errors import InvalidInputError, NoPathError
from usar_arm.core.spatial import Array

log = logging.getLogger("usar_arm.planning")

PLANNERS = ("RRTConnect", "RRT", "RRTstar", "InformedRRTstar", "SORRTstar", "BITstar",
            "AORRTC", "PRM", "PRMstar", "KPIECE1", "BKPIECE1", "LBKPIECE1", "FMT", "BFMT")
"""Geometric planners of the ompl wheel usable by name."""
COMPILED = "CompiledRRTConnect"
"""usar-arm's own RRT-Connect and shortcutting in one compiled call over the compiled verdicts
(:mod:`.compiled_plan`), OMPL's RRTConnect where it finds nothing: the default."""
FALLBACK = "RRTConnect"
"""OMPL's planner where the compiled one finds no path, and :func:`plan_path`'s for
:data:`COMPILED` (it plans with OMPL only)."""
CHOICES = (COMPILED, *PLANNERS)
"""Every planner name :class:`OmplOptions` takes: the compiled one, then OMPL's."""
PROJECTED = frozenset({"KPIECE1", "BKPIECE1", "LBKPIECE1"})
"""Planners that grid a projection of the space: they get the projection the MoveIt package's
``ompl_planning.yaml`` names (``joints(a1,a2)``: the first two joints' values, in cells of
:data:`PROJECTION_CELL`, as MoveIt's joint projection), not OMPL's random one."""
PROJECTION_CELL = 0.1
"""rad (m for a prismatic joint): cell size of that projection (MoveIt's default)."""

WIDE_EDGES = 30
"""Edges RRT-Connect checks with OMPL's own step (a fifth of the space's extent) before it takes
:data:`NARROW` steps: see :func:`_solve`. (It was 100: the Panda's MotionBenchMaker plans, which
check many more edges than that, then spent most of their time on long edges the shelves
block; the KR60's, the Fanuc's and the UR5's problems mostly need far fewer.)"""
NARROW = 0.04
"""Step of the narrow phase, as a fraction of the space's extent."""

_seeded: list[int] = []
ou.setLogLevel(ou.LogLevel.LOG_WARN)


@dataclass(frozen=True)
class OmplOptions:
    """Options of a joint-space plan.

    Attributes:
        planner: :data:`COMPILED` (the default) or one of OMPL's :data:`PLANNERS`
            (RRTConnect is MoveIt's default).
        time_limit: planning budget (s).
        resolution: largest joint change (rad or m) between checked configurations on an edge.
        max_step: largest distance (m) any point of the robot moves between checked
            configurations on the returned path's edges (bounded through each joint's lever
            arm); see :func:`~usar_arm.planning.ptp.plan_to_joints`.
        simplify: shortcut and reduce the path (checked edges only).
        seed: seed of OMPL's RNG (effective for the first plan of a process).
    """

    planner: str = COMPILED
    time_limit: float = 2.0
    resolution: float = 0.01
    max_step: float = 0.005
    simplify: bool = True
    seed: int = 0

    def __post_init__(self) -> None:
        if self.planner not in CHOICES:
            raise InvalidInputError(f"unknown planner '{self.planner}'; planners: "
                                    f"{', '.join(CHOICES)}")
        if not self.time_limit > 0:
            raise InvalidInputError(f"time limit must be > 0 s, got {self.time_limit}")
        if not self.resolution > 0:
            raise InvalidInputError(f"edge resolution must be > 0, got {self.resolution}")
        if not self.max_step > 0:
            raise InvalidInputError(f"edge step must be > 0 m, got {self.max_step}")
        if self.seed < 0:
            raise InvalidInputError(f"seed must be >= 0, got {self.seed}")


@dataclass(frozen=True)
class OmplResult:
    """A path (k, n waypoints, start first) and what it cost."""

    waypoints: Array
    planner: str
    planning_seconds: float
    simplify_seconds: float
    states_checked: int
    edges_checked: int


def edge_steps(a: Array, b: Array, resolution: float, levers: Array | None = None,
               max_step: float = math.inf) -> int:
    """How many steps the segment a -> b is checked in (see :func:`edge_configurations`)."""
    delta = np.abs(np.asarray(b, float) - np.asarray(a, float))
    steps = max(1, math.ceil(float(delta.max()) / resolution))  # (the method: half the cost)
    if levers is not None and math.isfinite(max_step):
        steps = max(steps, math.ceil(float(levers @ delta) / max_step))
    return steps


def edge_configurations(a: Array, b: Array, resolution: float, levers: Array | None = None,
                        max_step: float = math.inf) -> Array:
    """Configurations along a -> b, at most ``resolution`` apart per joint, both ends included,
    ordered coarse-to-fine (ends, middle, quarters, ...) so early entries find most blocks.

    With ``levers`` (per joint, m per rad or m: see
    :meth:`~usar_arm.planning.collision.CollisionWorld.lever_arms`), also close enough that no
    point of the robot moves more than ``max_step`` (m) between neighbours: a joint step of
    0.01 rad moves a point 2.9 m from the KR60's first axis by 29 mm, enough to clip a thin
    shelf board between two checks.
    """
    steps = edge_steps(a, b, resolution, levers, max_step)
    fractions = np.linspace(0.0, 1.0, steps + 1)
    levels = [np.array([0, steps])]
    seen = np.zeros(steps + 1, dtype=bool)
    seen[[0, steps]] = True
    stride = steps
    while stride > 1:  # halve the stride: the midpoints not yet taken, left to right
        stride //= 2
        ks = np.arange(stride, steps, stride)
        ks = ks[~seen[ks]]
        seen[ks] = True
        levels.append(ks)
    levels.append(np.flatnonzero(~seen))
    order = np.concatenate(levels)
    return a + (b - a) * fractions[order][:, None]


def reseed(seed: int) -> None:
    """Make the next plan of this process depend on ``seed`` alone.

    OMPL draws every RNG's seed from one process-global generator, and each plan here creates
    its own state space, planner and simplifier (so its own RNGs). Seeding that generator
    right before a plan therefore makes the plan the same whatever this process planned
    before (measured: a plan after three others equals the same plan in a fresh process).
    OMPL still prints that changing the seed after sampling started is not deterministic, which
    holds for RNGs created earlier, not for ours: the message is silenced for this call.
    """
    if seed < 0:
        raise InvalidInputError(f"seed must be >= 0, got {seed}")
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)
    try:
        ou.RNG.setSeed(int(seed) + 1)  # OMPL refuses 0
    finally:
        ou.setLogLevel(level)
    _seeded[:] = [int(seed)]


def draw_seed(first: int = 0) -> int:
    """A seed for a planner of usar-arm's own, drawn from OMPL's process-global generator: a
    plan seeded so depends on what :func:`reseed` (or, with ``first``, the process's first
    plan) set, exactly as an OMPL planner's plan does."""
    if not _seeded:
        reseed(first)
    return int(ou.RNG().uniformInt(0, 2**31 - 2))


def _project_first_joints(space: ob.RealVectorStateSpace) -> None:
    """Make the values of the first two joints, in :data:`PROJECTION_CELL` cells, the space's
    default projection."""
    projection = ob.RealVectorOrthogonalProjectionEvaluator(space, [0, 1])
    projection.inferCellSizes()  # (the cells exist only then)
    for k in range(2):
        projection.setCellSizes(k, PROJECTION_CELL)
    space.registerDefaultProjection(projection)


def _solve(ss: og.SimpleSetup, planner: ob.Planner, space: ob.StateSpace,
           counts: dict[str, int], time_limit: float) -> object:
    """Run the planner; RRT-Connect in two phases.

    RRT-Connect's step is all or nothing: an extension whose straight edge is blocked anywhere
    adds nothing. OMPL's default step (a fifth of the space's extent, 2.6 rad for the Panda)
    crosses an open scene in a few edges, but among shelves most such edges are blocked and the
    trees hardly grow. So the trees grow with the default step for :data:`WIDE_EDGES` edge
    checks; if they have not met by then, they keep growing (the same trees) with steps of
    :data:`NARROW` of the extent. The switch counts edges, not seconds, so a seeded plan stays
    reproducible.
    """
    if not isinstance(planner, og.RRTConnect):
        return ss.solve(time_limit)
    deadline = time.perf_counter() + time_limit
    wide = ob.PlannerTerminationCondition(
        lambda: counts["edges"] >= WIDE_EDGES or time.perf_counter() >= deadline)
    status = ss.solve(wide)
    left = deadline - time.perf_counter()
    if ss.haveExactSolutionPath() or left <= 0:
        return status
    planner.setRange(NARROW * space.getMaximumExtent())
    return ss.solve(left)


def plan_path(lower: Array, upper: Array, start: Array, goal: Array,
              state_valid: Callable[[Array], bool],
              segment_free: Callable[[Array, Array, int], bool], options: OmplOptions,
              levers: Array | None = None) -> OmplResult:
    """A collision-free joint path from ``start`` to ``goal``.

    Args:
        state_valid: True when one configuration is allowed.
        segment_free: given a, b and a number of steps, True when every configuration of the
            evenly stepped segment is allowed (the edge check, one call per edge; see
            ``CollisionWorld.segment_free``).
        levers: per joint, how far (m) a point of the robot moves per unit of the joint; with
            them, edges are checked every ``options.max_step`` m of motion as well.

    Raises:
        NoPathError: no path within the time limit (naming the planner and the budget).
    """
    if not _seeded:
        ou.RNG.setSeed(int(options.seed) + 1)  # OMPL refuses 0
        _seeded.append(int(options.seed))
    elif _seeded[0] != options.seed:
        log.debug("OMPL was seeded with %d by this process's first plan; seed %d has no effect",
                  _seeded[0], options.seed)
    n = len(start)
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(lower[i]))
        bounds.setHigh(i, float(upper[i]))
    space.setBounds(bounds)
    if options.planner in PROJECTED and n >= 2:
        _project_first_joints(space)
    ss = og.SimpleSetup(space)
    counts = {"states": 0, "edges": 0}

    def to_array(state: object) -> Array:
        return np.array([state[i] for i in range(n)])  # type: ignore[index]

    def valid(state: object) -> bool:
        counts["states"] += 1
        return bool(state_valid(to_array(state)))

    ss.setStateValidityChecker(valid)
    si = ss.getSpaceInformation()

    class EdgeValidator(ob.MotionValidator):
        def checkMotion(self, *args: object) -> bool:
            counts["edges"] += 1
            a, b = to_array(args[0]), to_array(args[1])
            return segment_free(a, b, edge_steps(a, b, options.resolution, levers,
                                                 options.max_step))

    validator = EdgeValidator(si)
    si.setMotionValidator(validator)
    s, g = space.allocState(), space.allocState()
    for i in range(n):
        s[i], g[i] = float(start[i]), float(goal[i])
    ss.setStartAndGoalStates(s, g)
    name = FALLBACK if options.planner == COMPILED else options.planner
    planner = getattr(og, name)(si)
    ss.setPlanner(planner)
    begin = time.perf_counter()
    status = _solve(ss, planner, space, counts, options.time_limit)
    planning = time.perf_counter() - begin
    if not ss.haveExactSolutionPath():
        raise NoPathError(name, options.time_limit, f"{status}; {counts['states']} states "
                          f"and {counts['edges']} edges checked")
    simplify = 0.0
    path = ss.getSolutionPath()
    if options.simplify:
        begin = time.perf_counter()
        simplifier = og.PathSimplifier(si)
        simplifier.reduceVertices(path)
        simplifier.partialShortcutPath(path)
        simplifier.reduceVertices(path)
        simplify = time.perf_counter() - begin
    waypoints = np.array([to_array(path.getState(k)) for k in range(path.getStateCount())])
    waypoints[0], waypoints[-1] = start, goal
    return OmplResult(waypoints, name, planning, simplify, counts["states"],
                      counts["edges"])
