"""A FollowJointTrajectory goal as plain data: checked the way ros2_control's
joint_trajectory_controller checks it, then turned into a usar-arm :class:`Trajectory`.

No ROS types here (the node converts messages to :class:`TrajectoryGoal`), so every rule is a
plain function with plain tests. Units: rad or m, s.

Rules (each failure is a :class:`GoalRejected` with the controller's error code):

* joint names: none missing, none unknown, none twice (INVALID_JOINTS);
* points: at least one; per point as many positions as joints, velocities and accelerations
  empty or as many (accelerations are checked, not followed); every number finite; times
  strictly increasing; at most ``MAX_DURATION_S`` long (INVALID_GOAL);
* the header stamp, when set, plus the last point's time lies in the future
  (OLD_HEADER_TIMESTAMP);
* every position inside the joint limits, every velocity the trajectory needs within the
  velocity limits (INVALID_GOAL): refused before anything moves;
* a first point at time 0 must be where the arm is (within ``start_tolerance``); a first point
  later than 0 is reached from where the arm is (INVALID_GOAL otherwise).

Points are joined by cubic segments through the given velocities (zero where none are given:
the arm rests at every such point), sampled at ``rate_hz``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from usar_arm.control.trajectory import MotionLimits, Trajectory
from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array

SUCCESSFUL = 0
INVALID_GOAL = -1
INVALID_JOINTS = -2
OLD_HEADER_TIMESTAMP = -3
PATH_TOLERANCE_VIOLATED = -4
GOAL_TOLERANCE_VIOLATED = -5


MAX_DURATION_S = 600.0
"""The longest goal (s): its samples are held in memory (100 Hz: about 9 MB for 600 s)."""


class GoalRejected(Exception):
    """A goal that is not executed; ``code`` is the FollowJointTrajectory error code."""

    def __init__(self, code: int, message: str):
        self.code = code
        self.message = message
        super().__init__(message)


@dataclass(frozen=True)
class TrajectoryGoal:
    """A joint trajectory and its tolerances.

    Attributes:
        joint_names: the order of every point's values.
        times: (k,) each point's time from the start (s).
        positions: k sequences (rad or m); velocities, accelerations: k sequences, each
            empty or as long as ``joint_names``.
        stamp: the header's start time (s on the node's clock), 0 = start now.
        path_tolerance, goal_tolerance: joint name -> position bound (rad or m); 0 = the
            node's default, negative = unbounded.
        goal_time_tolerance: s after the end within which the goal tolerance must hold.
    """

    joint_names: tuple[str, ...]
    times: tuple[float, ...]
    positions: tuple[tuple[float, ...], ...]
    velocities: tuple[tuple[float, ...], ...] = ()
    accelerations: tuple[tuple[float, ...], ...] = ()
    stamp: float = 0.0
    path_tolerance: dict[str, float] = field(default_factory=dict)
    goal_tolerance: dict[str, float] = field(default_factory=dict)
    goal_time_tolerance: float = 0.0


@dataclass(frozen=True)
class CheckedGoal:
    """A goal that passed :func:`check_goal`.

    Attributes:
        trajectory: in the arm's joint order, from the arm's current position, sampled.
        path_tolerance, goal_tolerance: per joint in the arm's order (inf = unbounded).
        start_delay: s to wait before starting (a header stamp in the future).
    """

    trajectory: Trajectory
    path_tolerance: Array
    goal_tolerance: Array
    goal_time_tolerance: float
    start_delay: float


def _check_names(goal: TrajectoryGoal, names: Sequence[str]) -> list[int]:
    """The column in the goal of each of the arm's joints."""
    given = list(goal.joint_names)
    unknown = [n for n in given if n not in names]
    twice = sorted({n for n in given if given.count(n) > 1})
    missing = [n for n in names if n not in given]
    if not given or unknown or twice or missing:
        parts = [f"unknown {unknown}" if unknown else "", f"repeated {twice}" if twice else "",
                 f"missing {missing}" if missing else "", "none given" if not given else ""]
        raise GoalRejected(INVALID_JOINTS, "joint names " + "; ".join(p for p in parts if p)
                           + f": expected each of {list(names)} once")
    return [given.index(n) for n in names]


def _matrix(rows: tuple[tuple[float, ...], ...], what: str, k: int, n: int,
            optional: bool) -> Array | None:
    """The (k, n) values of one kind, or None when all rows are empty and that is allowed."""
    if optional and all(len(r) == 0 for r in rows):
        return None
    if len(rows) != k or any(len(r) != n for r in rows):
        sizes = sorted({len(r) for r in rows})
        raise GoalRejected(INVALID_GOAL, f"every point needs {n} {what} (one per joint name)"
                           f"{' or none' if optional else ''}; got sizes {sizes}")
    out = np.array(rows, dtype=float)
    if not np.all(np.isfinite(out)):
        raise GoalRejected(INVALID_GOAL, f"{what} must be finite numbers")
    return out


def _tolerances(given: dict[str, float], names: Sequence[str], default: float) -> Array:
    out = np.full(len(names), default)
    for name, value in given.items():
        if name not in names:
            raise GoalRejected(INVALID_JOINTS, f"a tolerance names joint {name!r}: expected "
                                               f"one of {list(names)}")
        if not math.isfinite(value):
            raise GoalRejected(INVALID_GOAL, f"the tolerance of {name} is not finite")
        if value != 0:
            out[names.index(name)] = value if value > 0 else math.inf
    return out


def check_goal(goal: TrajectoryGoal, chain: KinematicChain, current: Array, now: float,
               rate_hz: float = 100.0, start_tolerance: float = 0.05,
               default_tolerances: tuple[float, float] = (math.inf, math.inf)) -> CheckedGoal:
    """Check ``goal`` against the arm (its chain, its ``current`` joints) at time ``now`` (s,
    the stamp's clock) and build the trajectory to execute.

    Raises:
        GoalRejected: the first rule broken (see the module docstring).
    """
    names = list(chain.joint_names)
    order = _check_names(goal, names)
    k, n = len(goal.positions), len(goal.joint_names)
    if k == 0:
        raise GoalRejected(INVALID_GOAL, "the trajectory has no points")
    times = np.array(goal.times, dtype=float)
    if len(times) != k or not np.all(np.isfinite(times)) or np.any(times < 0) \
            or np.any(np.diff(times) <= 0):
        raise GoalRejected(INVALID_GOAL, "time_from_start must be finite, non-negative and "
                                         f"strictly increasing; got {times.round(4).tolist()}")
    if times[-1] > MAX_DURATION_S:
        raise GoalRejected(INVALID_GOAL, f"the trajectory lasts {times[-1]:.0f} s; this node "
                                         f"runs at most {MAX_DURATION_S:.0f} s per goal")
    q = _matrix(goal.positions, "positions", k, n, optional=False)
    assert q is not None
    qd = _matrix(goal.velocities, "velocities", k, n, optional=True)
    _matrix(goal.accelerations, "accelerations", k, n, optional=True)  # checked, not used
    q, qd = q[:, order], (np.zeros_like(q) if qd is None else qd[:, order])
    delay = 0.0
    if goal.stamp > 0:
        if goal.stamp + times[-1] < now:
            raise GoalRejected(OLD_HEADER_TIMESTAMP, f"the trajectory ended "
                               f"{now - goal.stamp - times[-1]:.3f} s ago (header stamp "
                               f"{goal.stamp:.3f} s + {times[-1]:.3f} s, now {now:.3f} s)")
        delay = max(0.0, goal.stamp - now)
        if delay > MAX_DURATION_S:
            raise GoalRejected(INVALID_GOAL, f"the header stamp is {delay:.0f} s in the future; "
                               f"at most {MAX_DURATION_S:.0f} s is waited for")
    _check_limits(q, chain)
    if times[0] == 0:
        gap = np.abs(q[0] - current)
        j = int(np.argmax(gap))
        if gap[j] > start_tolerance:
            raise GoalRejected(INVALID_GOAL, f"the first point (time 0) has {names[j]} = "
                               f"{q[0, j]:.4f} but the arm is at {current[j]:.4f} (start "
                               f"tolerance {start_tolerance}): begin the trajectory at the "
                               "current state or give its first point a time > 0")
        q[0] = current
    else:
        times = np.concatenate([[0.0], times])
        q = np.vstack([current, q])
        qd = np.vstack([np.zeros(len(names)), qd])
    trajectory = sample(names, times, q, qd, chain, rate_hz)
    path = _tolerances(goal.path_tolerance, names, default_tolerances[0])
    final = _tolerances(goal.goal_tolerance, names, default_tolerances[1])
    return CheckedGoal(trajectory, path, final, max(0.0, goal.goal_time_tolerance), delay)


def _check_limits(q: Array, chain: KinematicChain) -> None:
    lower, upper = chain.lower(), chain.upper()
    outside = (q < lower - 1e-9) | (q > upper + 1e-9)
    if np.any(outside):
        i, j = (int(v) for v in np.argwhere(outside)[0])
        raise GoalRejected(INVALID_GOAL, f"point {i} puts {chain.joint_names[j]} at "
                           f"{q[i, j]:.4f}, outside its limits [{lower[j]:.4f}, "
                           f"{upper[j]:.4f}]")


def sample(names: Sequence[str], times: Array, q: Array, qd: Array, chain: KinematicChain,
           rate_hz: float) -> Trajectory:
    """Cubic Hermite segments through (times, q, qd), sampled on a uniform grid of about
    1/rate_hz s.

    Raises:
        GoalRejected: a sampled velocity exceeds a joint's velocity limit (INVALID_GOAL).
    """
    steps = max(1, math.ceil(times[-1] * rate_hz - 1e-9))
    t = np.linspace(0.0, max(float(times[-1]), 1.0 / rate_hz), steps + 1)  # uniform grid
    seg = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2) \
        if len(times) > 1 else np.zeros(len(t), dtype=int)
    if len(times) == 1:
        pos = np.repeat(q[:1], len(t), axis=0)
        vel = np.zeros_like(pos)
    else:
        h = (times[seg + 1] - times[seg])[:, None]
        s = ((t - times[seg])[:, None] / h).clip(0.0, 1.0)
        p0, p1, v0, v1 = q[seg], q[seg + 1], qd[seg] * h, qd[seg + 1] * h
        s2, s3 = s * s, s * s * s
        pos = ((2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * v0 + (-2 * s3 + 3 * s2) * p1
               + (s3 - s2) * v1)
        vel = ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * v0 + (-6 * s2 + 6 * s) * p1
               + (3 * s2 - 2 * s) * v1) / h
    limits = MotionLimits.from_chain(chain)
    excess = np.abs(vel) / limits.velocity
    if np.max(excess, initial=0.0) > 1.0 + 1e-6:
        i, j = (int(v) for v in np.unravel_index(int(np.argmax(excess)), excess.shape))
        raise GoalRejected(INVALID_GOAL, f"the trajectory needs {abs(vel[i, j]):.3f} /s on "
                           f"{names[j]} at t = {t[i]:.2f} s, above its velocity limit "
                           f"{limits.velocity[j]:.3f}: give the points more time")
    acc = np.gradient(vel, t, axis=0) if len(t) > 1 else np.zeros_like(vel)
    return Trajectory(tuple(names), t, pos, vel, acc, q.copy(), limits, motion="ptp",
                      mode="ros")
