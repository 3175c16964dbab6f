"""Time-parameterisation with Ruckig (community edition, offline, state-to-state calls only).

Three ways to time a path:

* :func:`stop_at_waypoints` (PTP default): each path segment from rest to rest, timed by a
  jerk-limited Ruckig profile of its path parameter (limits = the tightest joint's limit over its
  share of the segment), so the arm moves exactly along the collision-checked straight segments
  (Ruckig's multi-DoF phase synchronisation is not always possible and then bends the path).
* :func:`blended` (PTP ``--blend``): the arm passes through the waypoints with chosen velocities;
  every blended segment is re-checked (position limits, which Ruckig's community edition does not
  enforce, and collisions through a callback) and falls back to stop-at-both-ends where the check
  fails.
* :func:`along_path` (LIN): one scalar jerk-limited Ruckig profile of the path parameter s, with
  s-limits derived from the path's derivatives so that every joint stays within its limits.

The result is a :class:`TimedMotion`, which can be sampled at any rate.

This is the only module that imports ``ruckig``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np
from ruckig import InputParameter, Result, Ruckig, Synchronization
from ruckig import Trajectory as RuckigTrajectory

from usar_arm.control.trajectory import MotionLimits, Trajectory
from usar_arm.core.errors import TimingError
from usar_arm.core.spatial import Array

DEFAULT_RATE_HZ = 500.0
"""Sample rate of the trajectories the planner returns (>= 250 Hz)."""
PASS_THROUGH_FRACTION = 0.9
"""Blend: pass-through velocities stay this fraction below the velocity limits (Ruckig needs
consistent target states)."""

if TYPE_CHECKING:  # scipy.interpolate costs ~0.4 s of start-up; only LIN timing needs it
    from scipy.interpolate import CubicSpline

SampleCheck = Callable[[Array], Array]
"""Given configurations (m, n), True where a configuration is not allowed (collision)."""


def _calculate(start: Array, target: Array, v0: Array, v1: Array, limits: MotionLimits,
               sync: Synchronization) -> RuckigTrajectory:
    dof = len(start)
    otg = Ruckig(dof)
    inp = InputParameter(dof)
    inp.current_position = start.tolist()
    inp.current_velocity = v0.tolist()
    inp.current_acceleration = [0.0] * dof
    inp.target_position = target.tolist()
    inp.target_velocity = v1.tolist()
    inp.target_acceleration = [0.0] * dof
    inp.max_velocity = limits.velocity.tolist()
    inp.max_acceleration = limits.acceleration.tolist()
    inp.max_jerk = limits.jerk.tolist()
    inp.synchronization = sync
    traj = RuckigTrajectory(dof)
    result = otg.calculate(inp, traj)
    if result not in (Result.Working, Result.Finished):
        raise TimingError(f"Ruckig could not time a segment ({result.name}) from "
                          f"{np.round(start, 4).tolist()} to {np.round(target, 4).tolist()}")
    return traj


def _phase_table(profile: Any) -> tuple[Array, Array, Array, Array, Array]:
    """One DoF's Ruckig profile as constant-jerk phases: start times (s), jerk, and position,
    velocity, acceleration at each phase's start; the last row is the final state (jerk 0).

    Ruckig runs an optional two-phase brake pre-trajectory first, then the seven phases of the
    main profile; after its end the state moves on with its final acceleration.
    """
    brake = profile.brake
    if profile.accel.duration > 0.0:
        raise TimingError("Ruckig returned an acceleration pre-trajectory, which the "
                          "vectorised sampler does not model")
    b_t = np.asarray(brake.t, float)
    t = np.concatenate([b_t, np.asarray(profile.t, float)])
    starts = np.concatenate([[0.0], np.cumsum(t)])
    jerk = np.concatenate([np.asarray(brake.j, float), np.asarray(profile.j, float),
                           [0.0]])
    pos = np.concatenate([np.asarray(brake.p, float), np.asarray(profile.p, float)])
    vel = np.concatenate([np.asarray(brake.v, float), np.asarray(profile.v, float)])
    acc = np.concatenate([np.asarray(brake.a, float), np.asarray(profile.a, float)])
    return starts, jerk, pos, vel, acc


def profile_states(traj: RuckigTrajectory, times: Array) -> tuple[Array, Array, Array]:
    """Positions, velocities and accelerations (m, dof) of a Ruckig trajectory at ``times``
    (s, clipped to [0, duration]), evaluated for all times at once.

    Each DoF is piecewise constant-jerk: within a phase that starts at t_k with state
    (p_k, v_k, a_k) and jerk j_k, p = p_k + v_k dt + a_k dt^2/2 + j_k dt^3/6 (dt = t - t_k).
    Equal to Ruckig's own ``at_time`` to rounding (tested).
    """
    times = np.clip(np.asarray(times, float), 0.0, float(traj.duration))
    dof = traj.degrees_of_freedom
    out = np.empty((3, len(times), dof))
    for d, profile in enumerate(traj.profiles[-1]):
        starts, jerk, p, v, a = _phase_table(profile)
        k = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(jerk) - 1)
        dt = times - starts[k]
        j = jerk[k]
        out[2, :, d] = a[k] + j * dt
        out[1, :, d] = v[k] + (a[k] + 0.5 * j * dt) * dt
        out[0, :, d] = p[k] + (v[k] + (0.5 * a[k] + j * dt / 6.0) * dt) * dt
    return out[0], out[1], out[2]


@dataclass
class _Straight:
    """A rest-to-rest straight segment a -> a + delta, timed by a 1-DoF profile of s in [0, 1]:
    exactly on the line (multi-DoF phase synchronisation is not always possible)."""

    start: Array
    delta: Array
    profile: RuckigTrajectory

    @property
    def duration(self) -> float:
        return float(self.profile.duration)

    def states(self, times: Array) -> tuple[Array, Array, Array]:
        """Positions, velocities, accelerations (m, n) at segment times ``times`` (s)."""
        gap_s, gap_sd = self.end_gaps
        s, sd, sdd = _closed(times, self.duration, profile_states(self.profile, times), gap_s,
                             gap_sd)
        return (self.start + s * self.delta, sd * self.delta, sdd * self.delta)

    @cached_property
    def end_gaps(self) -> tuple[float, float]:
        """How far the profile ends from s = 1 and from rest (rounding, ~1e-9)."""
        s, sd, _ = profile_states(self.profile, np.array([self.duration]))
        return 1.0 - float(s[0, 0]), -float(sd[0, 0])

    @property
    def peak_speed(self) -> float:
        """Largest ds/dt of the profile (1/s)."""
        _, sd, _ = profile_states(self.profile, np.linspace(0.0, self.duration, 21))
        return float(np.max(np.abs(sd)))


@dataclass
class _Free:
    """A multi-DoF Ruckig segment between two states (used where the motion blends)."""

    traj: RuckigTrajectory
    end_position: Array
    end_velocity: Array

    @property
    def duration(self) -> float:
        return float(self.traj.duration)

    def states(self, times: Array) -> tuple[Array, Array, Array]:
        """Positions, velocities, accelerations (m, n) at segment times ``times`` (s)."""
        gap_q, gap_qd = self.end_gaps
        return _closed(times, self.duration, profile_states(self.traj, times), gap_q, gap_qd)

    @cached_property
    def end_gaps(self) -> tuple[Array, Array]:
        """How far the profile ends from the target position and velocity (~1e-8)."""
        q, qd, _ = profile_states(self.traj, np.array([self.duration]))
        return self.end_position - q[0], self.end_velocity - qd[0]


def _closed(times: Array, duration: float, states: tuple[Array, Array, Array],
            position_gap: Array | float, velocity_gap: Array | float
            ) -> tuple[Array, Array, Array]:
    """``states`` (positions, velocities, accelerations at ``times``, s) plus the quintic that
    closes the profile's gap at its end: Ruckig's profile ends within ~1e-8 of its target
    (rad or m; rad/s), and the next segment starts exactly there, so without it the motion
    would jump by that much where two segments meet, a jerk of gap / h^3 to anyone who
    differentiates 1 ms samples. The quintic starts with zero position, velocity and
    acceleration and ends with the gaps and zero acceleration; its jerk is at most
    60 gap / T^3 + 36 velocity_gap / T^2 (about 1e-6 rad/s^3 for T = 0.1 s)."""
    if duration <= 0.0:
        return states
    s = np.clip(np.asarray(times, float) / duration, 0.0, 1.0)[:, None]
    dp = np.atleast_1d(np.asarray(position_gap, float))
    dv = np.atleast_1d(np.asarray(velocity_gap, float)) * duration
    h0 = s ** 3 * (10.0 + s * (-15.0 + 6.0 * s))
    h0d = s ** 2 * (30.0 + s * (-60.0 + 30.0 * s))
    h0dd = s * (60.0 + s * (-180.0 + 120.0 * s))
    h1 = s ** 3 * (-4.0 + s * (7.0 - 3.0 * s))
    h1d = s ** 2 * (-12.0 + s * (28.0 - 15.0 * s))
    h1dd = s * (-24.0 + s * (84.0 - 60.0 * s))
    q, qd, qdd = states
    return (q + (dp * h0 + dv * h1).reshape(q.shape),
            qd + ((dp * h0d + dv * h1d) / duration).reshape(qd.shape),
            qdd + ((dp * h0dd + dv * h1dd) / duration ** 2).reshape(qdd.shape))


Segment = _Straight | _Free


def _scalar_profile(length: float, v: float, a: float, j: float, name: str
                    ) -> RuckigTrajectory:
    otg = Ruckig(1)
    inp = InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [length], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v], [a], [j]
    profile = RuckigTrajectory(1)
    result = otg.calculate(inp, profile)
    if result not in (Result.Working, Result.Finished):
        raise TimingError(f"Ruckig could not time the {name} ({result.name})")
    return profile


def straight(a: Array, b: Array, limits: MotionLimits) -> _Straight:
    """The time-optimal rest-to-rest motion along the segment a -> b under the joint limits."""
    delta = b - a
    moving = np.abs(delta) > 1e-12
    if not np.any(moving):
        return _Straight(a, delta, _scalar_profile(0.0, 1.0, 1.0, 1.0, "segment"))
    span = np.abs(delta[moving])
    v = float(np.min(limits.velocity[moving] / span))
    acc = float(np.min(limits.acceleration[moving] / span))
    jerk = float(np.min(limits.jerk[moving] / span))
    return _Straight(a, delta, _scalar_profile(1.0, v, acc, jerk, "segment"))


@dataclass
class TimedMotion:
    """A continuous-time motion: Ruckig segments in sequence, or an s-profile along a path."""

    joint_names: tuple[str, ...]
    limits: MotionLimits
    waypoints: Array
    mode: str
    segments: list[Segment] = field(default_factory=list)
    starts: Array = field(default_factory=lambda: np.zeros(0))
    path: CubicSpline | None = None
    profile: RuckigTrajectory | None = None
    seconds: float = 0.0
    """Time spent computing the timing (s)."""
    fallbacks: int = 0
    """Blend: segments that had to stop at their ends."""

    @property
    def duration(self) -> float:
        """Duration (s)."""
        if self.profile is not None:
            return float(self.profile.duration)
        return float(self.starts[-1] + self.segments[-1].duration) if self.segments else 0.0

    def evaluate(self, times: Array) -> tuple[Array, Array, Array]:
        """Positions, velocities, accelerations (m, n) at ``times`` (s)."""
        times = np.clip(np.asarray(times, float), 0.0, self.duration)
        n = len(self.joint_names)
        q, qd, qdd = (np.empty((len(times), n)) for _ in range(3))
        if self.profile is not None:
            assert self.path is not None
            pos, vel, acc = (x[:, 0] for x in profile_states(self.profile, times))
            d1, d2 = self.path(pos, 1), self.path(pos, 2)
            q[:] = self.path(pos)
            qd[:] = d1 * vel[:, None]
            qdd[:] = d2 * vel[:, None] ** 2 + d1 * acc[:, None]
            return q, qd, qdd
        index = np.clip(np.searchsorted(self.starts, times, side="right") - 1, 0,
                        len(self.segments) - 1)
        for i in np.unique(index):
            rows = index == i
            q[rows], qd[rows], qdd[rows] = self.segments[i].states(times[rows] - self.starts[i])
        return q, qd, qdd

    def sample(self, rate: float = DEFAULT_RATE_HZ, motion: str = "ptp") -> Trajectory:
        """Samples on a uniform grid of at least ``rate`` Hz that ends exactly at the end."""
        count = max(2, math.ceil(self.duration * rate) + 1)
        times = np.linspace(0.0, self.duration, count)
        q, qd, qdd = self.evaluate(times)
        qd[-1] = 0.0
        qdd[-1] = 0.0
        return Trajectory(self.joint_names, times, q, qd, qdd, self.waypoints, self.limits,
                          motion, self.mode, {"timing_seconds": self.seconds,
                                              "blend_fallbacks": self.fallbacks})


def stop_at_waypoints(names: tuple[str, ...], waypoints: Array, limits: MotionLimits
                      ) -> TimedMotion:
    """Rest at every waypoint; each segment a phase-synchronised straight line."""
    start = time.perf_counter()
    wp = _dedupe(np.asarray(waypoints, float))
    segments: list[Segment] = [straight(wp[k], wp[k + 1], limits) for k in range(len(wp) - 1)]
    return _assemble(names, limits, wp, "stop", segments, time.perf_counter() - start)


def blended(names: tuple[str, ...], waypoints: Array, limits: MotionLimits,
            forbidden: SampleCheck | None = None, check_step: float = 0.005) -> TimedMotion:
    """Pass through the waypoints without stopping, then re-check every segment.

    A segment whose samples (every ``check_step`` s) leave the position limits or hit
    ``forbidden`` is redone from rest to rest, and its neighbours are retimed to match. Never
    slower than resting at every waypoint: where passing through takes longer (a path whose
    pass-through velocities force long detours of the jerk-limited profile), the rest-to-rest
    timing is returned, with every interior waypoint counted as a fallback.
    """
    start = time.perf_counter()
    wp = _dedupe(np.asarray(waypoints, float))
    n_wp = len(wp)
    lines = [straight(wp[k], wp[k + 1], limits) for k in range(n_wp - 1)]
    vel = _pass_through(wp, lines, limits)
    stopped = np.zeros(n_wp, dtype=bool)
    stopped[[0, -1]] = True
    fallbacks = 0
    while True:
        v = np.where(stopped[:, None], 0.0, vel)
        segments: list[Segment] = []
        bad = None
        for k in range(n_wp - 1):
            if stopped[k] and stopped[k + 1]:
                segments.append(lines[k])
                continue
            seg = _Free(_calculate(wp[k], wp[k + 1], v[k], v[k + 1], limits,
                                   Synchronization.Time), wp[k + 1], v[k + 1])
            segments.append(seg)
            if bad is None and not _segment_ok(seg, limits, forbidden, check_step):
                bad = k
        if bad is None:
            break
        stopped[bad] = stopped[bad + 1] = True
        fallbacks += 1
    motion = _assemble(names, limits, wp, "blend", segments, time.perf_counter() - start)
    motion.fallbacks = fallbacks
    if fallbacks < n_wp - 2:
        straight_segments: list[Segment] = list(lines)
        rest = _assemble(names, limits, wp, "stop", straight_segments,
                         time.perf_counter() - start)
        if rest.duration < motion.duration:
            rest.fallbacks = n_wp - 2
            return rest
    return motion


def _pass_through(wp: Array, lines: list[_Straight], limits: MotionLimits) -> Array:
    """A velocity at each interior waypoint: the mean of the two neighbouring straight
    segments' peak velocity vectors, shrunk by how sharply the path turns (zero for a right
    angle or worse) and kept below the joint limits."""
    vel = np.zeros_like(wp)
    for k in range(1, len(wp) - 1):
        v_in = lines[k - 1].peak_speed * lines[k - 1].delta
        v_out = lines[k].peak_speed * lines[k].delta
        a, b = lines[k - 1].delta, lines[k].delta
        cos_turn = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
        if cos_turn <= 0.0:
            continue
        v = 0.5 * (v_in + v_out) * cos_turn
        over = np.max(np.abs(v) / (PASS_THROUGH_FRACTION * limits.velocity))
        vel[k] = v / max(1.0, float(over))
    return vel


def _segment_ok(seg: _Free, limits: MotionLimits, forbidden: SampleCheck | None,
                step: float) -> bool:
    times = np.append(np.arange(0.0, seg.duration, step), seg.duration)
    q = seg.states(times)[0]
    extremes = seg.states(_turning_times(seg.traj))[0]
    for x in (q, extremes):
        if np.any(x < limits.lower - 1e-9) or np.any(x > limits.upper + 1e-9):
            return False
    return not (forbidden is not None and bool(np.any(forbidden(q))))


def _turning_times(traj: RuckigTrajectory) -> Array:
    """Every time (s) at which some DoF of ``traj`` may reach an extreme position: the phase
    boundaries and, inside each constant-jerk phase, the roots of its velocity
    v + a t + j t^2 / 2. A position check at these times is exact, not sampled."""
    out = [np.array([0.0, float(traj.duration)])]
    for profile in traj.profiles[-1]:
        starts, jerk, _, v, a = _phase_table(profile)
        span = np.diff(starts)
        j, v, a = jerk[:-1], v[:-1], a[:-1]
        out.append(starts)
        quad = np.abs(j) > 1e-12
        disc = np.where(quad, a * a - 2.0 * j * v, -1.0)
        root = np.sqrt(np.maximum(disc, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            roots = [((-a + root) / j, quad & (disc >= 0.0)),
                     ((-a - root) / j, quad & (disc >= 0.0)),
                     (-v / a, ~quad)]
        for cand, valid in roots:
            ok = valid & np.isfinite(cand) & (cand > 0.0) & (cand < span)
            out.append(starts[:-1][ok] + cand[ok])
    return np.unique(np.clip(np.concatenate(out), 0.0, float(traj.duration)))


def _dedupe(wp: Array) -> Array:
    keep = [0] + [k for k in range(1, len(wp)) if np.max(np.abs(wp[k] - wp[k - 1])) > 1e-9]
    out = wp[keep]
    if len(out) < 2:
        out = np.vstack([wp[0], wp[0]])
    return out


def _assemble(names: tuple[str, ...], limits: MotionLimits, wp: Array, mode: str,
              segments: list[Segment], seconds: float) -> TimedMotion:
    durations = np.array([seg.duration for seg in segments])
    starts = np.concatenate([[0.0], np.cumsum(durations)[:-1]])
    return TimedMotion(names, limits, wp, mode, segments, starts, seconds=seconds)


def along_path(names: tuple[str, ...], s: Array, q: Array, limits: MotionLimits,
               max_speed: float = math.inf, max_acceleration: float = math.inf
               ) -> TimedMotion:
    """Time a dense path q(s) with one jerk-limited profile of s (0 -> s[-1]).

    The joint velocity is q'(s) s', the acceleration q'' s'^2 + q' s'', the jerk
    q''' s'^3 + 3 q'' s' s'' + q' s'''. With the largest |q'|, |q''|, |q'''| along the path,
    s' <= v_s, |s''| <= a_s and |s'''| <= j_s are chosen so that every term stays within the
    joint's limit (half of the acceleration, a third of the jerk budget each), then Ruckig
    shapes the fastest profile of s under those bounds. ``max_speed``/``max_acceleration``
    cap s' and s'' (e.g. a Cartesian speed when s is the tool's path length).
    """
    start = time.perf_counter()
    from scipy.interpolate import CubicSpline

    spline = CubicSpline(s, q, axis=0)
    grid = np.linspace(s[0], s[-1], max(200, 4 * len(s)))
    m1 = np.abs(spline(grid, 1)).max(axis=0) + 1e-12
    m2 = np.abs(spline(grid, 2)).max(axis=0) + 1e-12
    m3 = np.abs(spline(grid, 3)).max(axis=0) + 1e-12
    vel, acc, jerk = limits.velocity, limits.acceleration, limits.jerk
    v_s = min(float(np.min(vel / m1)), float(np.min(np.sqrt(0.5 * acc / m2))),
              float(np.min(np.cbrt(jerk / (3 * m3)))), max_speed)
    a_s = min(float(np.min(0.5 * acc / m1)), float(np.min(jerk / (9 * m2 * v_s))),
              max_acceleration)
    j_s = float(np.min(jerk / (3 * m1)))
    profile = _scalar_profile(float(s[-1]), v_s, a_s, j_s, "path profile")
    return TimedMotion(names, limits, np.asarray(q), "lin", path=spline,
                       profile=profile, seconds=time.perf_counter() - start)
