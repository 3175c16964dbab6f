"""Streaming a trajectory to the arm: ACT out at a steady rate, ASTA in, measured and safe.

* **Streaming**: full ACT lines (0-based links) every 1/rate s on a monotonic clock; deadlines are
  ``t0 + k / rate`` (no drift); each target is the trajectory's position plus the drive model's
  lag compensation (:mod:`.drive`), always clamped into the joint limits.
* **Feedback**: every ASTA (10 Hz, 1-based links) is compared with where the trajectory was when
  it arrived; the largest difference is the tracking error.
* **Settling**: after the last point the final target is held and nudged (a bounded integral
  correction) until every joint is within the tolerance: a stiffness-only drive sags under
  gravity, and the correction removes that.
* **Safety**: too large a tracking error, feedback that stops (or comes too slowly, or is not
  finite), a line from the server that is not USARSim, a dropped connection or Ctrl-C stop the
  motion: the arm is told to hold where it is (when the connection still allows: at its measured
  position, or, when the feedback cannot be trusted, where the plan says it is now) and
  :class:`~usar_arm.core.errors.ExecutionAbortedError` says what happened, which joint, by how much,
  and when. Every wait for feedback is bounded by ``feedback_timeout``.
"""

from __future__ import annotations

import gc
import logging
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from usar_arm.control.drive import DriveModel, excitation, fit
from usar_arm.control.tool_accuracy import ToolAccuracy
from usar_arm.control.trajectory import ExecutedSamples, Trajectory
from usar_arm.core.errors import (
    ConnectionLostError,
    ExecutionAbortedError,
    ProtocolError,
    ResponseTimeoutError,
    UsarArmError,
)
from usar_arm.core.spatial import Array
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import Received, UsarClient

log = logging.getLogger("usar_arm.control")


@dataclass(frozen=True)
class ExecutionOptions:
    """How to execute.

    Attributes:
        rate_hz: ACT lines per second (default 100).
        settle_tolerance: rad (or m) every joint must reach after the motion (default 0.0001,
            the resolution UDK prints ASTA values with: 1e-4 rad at 2 m is 0.2 mm).
        settle_timeout: s to reach it.
        max_tracking_error: rad (or m): a larger error during the motion aborts it.
        feedback_timeout: s without ASTA that aborts the motion.
        start_tolerance: rad (or m): the arm must be this close to the trajectory's start.
        correction_limit: rad (or m): the largest settle correction of a target.
        feedforward: compensate each drive's lag (identified on the first execution).
    """

    rate_hz: float = 100.0
    settle_tolerance: float = 0.0001
    settle_timeout: float = 5.0
    max_tracking_error: float = 0.1
    feedback_timeout: float = 0.5
    start_tolerance: float = 0.05
    correction_limit: float = 0.05
    feedforward: bool = True


@dataclass(frozen=True)
class ExecutionReport:
    """What happened on the arm.

    Attributes:
        final_joint_error_rad: per joint, |measured - goal| after settling (rad or m).
        max_tracking_error_rad: the largest |measured - planned| during the motion.
        tracking_error_per_joint: its per-joint maxima.
        rate_hz: ACT lines per second achieved; jitter_p50_ms, jitter_p99_ms: how far the send
            times strayed from their deadlines.
        settled: every joint reached the tolerance; settle_seconds: how long that took.
        goal: the joint goal held at the end (the trajectory's last point, plus any tip
            correction); executed: the ASTA samples (time since the start, joints).
        tip: tool0's error at the end, added by the caller (None until then).
        started_at: when the first ACT was sent (time.perf_counter s): to place the motion
            on a longer timeline.
    """

    joint_names: tuple[str, ...]
    final_joint_error_rad: Array
    max_tracking_error_rad: float
    tracking_error_per_joint: Array
    rate_hz: float
    jitter_p50_ms: float
    jitter_p99_ms: float
    duration_s: float
    settled: bool
    settle_seconds: float
    goal: Array
    executed: ExecutedSamples
    tip: ToolAccuracy | None = None
    started_at: float = 0.0

    def as_json(self) -> dict[str, Any]:
        """The stable keys ``--json`` prints."""
        return {"final_joint_error_rad": float(np.max(self.final_joint_error_rad)),
                "final_joint_error_per_joint_rad": self.final_joint_error_rad.tolist(),
                "max_tracking_error_rad": self.max_tracking_error_rad,
                "tracking_error_per_joint_rad": self.tracking_error_per_joint.tolist(),
                "rate_hz": self.rate_hz, "jitter_p50_ms": self.jitter_p50_ms,
                "jitter_p99_ms": self.jitter_p99_ms, "duration_s": self.duration_s,
                "settled": self.settled, "settle_seconds": self.settle_seconds,
                "tip_error_m": None, "tip_error_rad": None,
                **(self.tip.as_json() if self.tip is not None else {})}


class _Feedback:
    """ASTA samples of one actuator, as (receipt time, joint values in joint order)."""

    def __init__(self, actuator: str, links: tuple[int, ...]):
        self.actuator = actuator
        self.links = links
        self.times: list[float] = []
        self.values: list[Array] = []
        self.sim_times: list[float] = []
        self.invalid: str | None = None
        """The first ASTA line whose values were not finite numbers (skipped)."""

    def __call__(self, rec: Received) -> None:
        msg = rec.message
        if isinstance(msg, m.Asta) and msg.name.lower() == self.actuator.lower():
            joints = msg.joints(self.links)
            if joints is not None:
                q = np.array(joints)
                if not (np.all(np.isfinite(q)) and np.isfinite(msg.time)):
                    self.invalid = self.invalid or rec.line
                    return
                self.values.append(q)
                self.times.append(rec.wall_time)
                self.sim_times.append(msg.time)

    def complete(self) -> int:
        """How many samples have all three fields in: the reader's thread appends them one
        after another, and may be doing so while another thread reads."""
        return min(len(self.values), len(self.times), len(self.sim_times))

    def sampled_at(self, i: int, count: int) -> float:
        """When (perf_counter s) sample ``i`` was taken: its simulated time plus the smallest
        receipt latency seen (the server's clock runs at wall speed; receipt times alone carry
        a few ms of jitter, which at 3 rad/s is a 0.01 rad error). ``count``: the samples that
        may be read (:meth:`complete`, taken once by the caller)."""
        lo = max(0, i - 20)  # a recent window: the server may re-anchor its clock when busy
        hi = min(i + 21, count)
        offset = min(t - s for t, s in zip(self.times[lo:hi], self.sim_times[lo:hi],
                                          strict=True))
        return self.sim_times[i] + offset


class Executor:
    """Executes trajectories on one actuator of a connected server.

    Args:
        client: the connection that owns the robot.
        actuator: its name (ACT/ASTA). links: USARSim link (1-based) of each joint, in order.
        names: the joint names.
        lower: each joint's lower limit (rad or m; targets are always clamped into the limits).
        upper: each joint's upper limit (rad or m).
        options: rates, tolerances, bounds.
    """

    def __init__(self, client: UsarClient, actuator: str, links: tuple[int, ...],
                 names: tuple[str, ...], lower: Array, upper: Array,
                 options: ExecutionOptions | None = None):
        self.client = client
        self.actuator = actuator
        self.links = links
        self.names = names
        self.lower = np.asarray(lower, float)
        self.upper = np.asarray(upper, float)
        self.options = options or ExecutionOptions()
        self.drive: DriveModel | None = None
        self._act_index = [k - 1 for k in links]
        self._holding: Array | None = None
        """The command that holds the arm where the plan has it now (updated while streaming)."""
        self._bad_lines = 0
        """The client's count of non-USARSim lines when the current execution began."""
        self._t0 = 0.0
        """When the current execution began, then when its motion began (perf_counter s)."""
        self.monitor: Callable[[float], str | None] | None = None
        """Asked every command period and every settling step with the time (s) since the
        motion began; a returned reason (a cancel, a path tolerance a caller checks) stops the
        motion: the arm holds where it is measured and :class:`ExecutionAbortedError` carries
        the reason."""

    # ------------------------------------------------------------------ low level
    def send(self, targets: Array) -> None:
        """One full ACT line (targets clamped into the limits; never a non-finite one)."""
        if not np.all(np.isfinite(targets)):  # before clipping, which would turn inf into a limit
            raise ExecutionAbortedError(f"refusing to command non-finite joint targets "
                                        f"{np.round(targets, 4).tolist()}")
        u = np.clip(targets, self.lower, self.upper)
        self.client.act(self.actuator, dict(zip(self._act_index, u.tolist(), strict=True)))

    def measure(self, timeout: float = 2.0, after: float | None = None) -> tuple[Array, float]:
        """The joints of the next ASTA (newer than simulated time ``after``) and its time.

        Raises:
            ResponseTimeoutError, ConnectionLostError: no such ASTA within ``timeout`` s.
            ProtocolError: the ASTA is unreadable, lacks a joint, or holds non-finite values.
        """
        asta = self.client.wait_asta(self.actuator, after_time=after, timeout=timeout)
        joints = asta.joints(self.links)
        if joints is None or not np.all(np.isfinite(joints)):
            line = self.client.latest_line("ASTA", self.actuator) or str(asta)
            missing = list(asta.missing(self.links))
            raise ProtocolError(line, 0, f"expected a finite {{Value}} for each of links "
                                         f"{list(self.links)} of {self.actuator}" +
                                (f"; links {missing} are missing" if missing else ""))
        return np.array(joints), asta.time

    def hold(self, command: Array | None = None) -> None:
        """Tell the arm to stay where it is now (best effort): send ``command``, or, without
        one, the measured joints of the latest ASTA (plus the drive's sag compensation)."""
        try:
            if command is None:
                q, _ = self.measure(timeout=0.3)
                command = self.drive.command(q, np.zeros_like(q)) if self.drive else q
            self.send(command)
            log.info("holding at %s", np.round(command, 4).tolist())
        except (UsarArmError, OSError) as exc:
            log.warning("could not command a hold: %s", exc)

    def _check_feedback(self, feedback: _Feedback, t0: float) -> None:
        """Abort (holding where the plan has the arm now) when the feedback is older than
        ``feedback_timeout`` s, was not finite, or the server sent a line that is not
        USARSim since the execution began."""
        now = time.perf_counter()
        problem = None
        new = self.client.bad_line_count - self._bad_lines
        if new > 0:
            bad = self.client.bad_lines[-new:][0]
            problem = f"the server sent a line that is not USARSim: {bad.error}"
        elif feedback.invalid is not None:
            problem = f"ASTA feedback is not finite: {feedback.invalid[:300]}"
        else:
            last = feedback.times[-1] if feedback.times else t0
            if now - last > self.options.feedback_timeout \
                    and now - t0 > self.options.feedback_timeout:
                problem = (f"no ASTA feedback for {now - last:.2f} s (bound "
                           f"{self.options.feedback_timeout} s)")
        if problem is not None:
            self.hold(self._holding)
            raise ExecutionAbortedError(problem, at_time_s=now - t0)
        reason = self.monitor(now - self._t0) if self.monitor is not None else None
        if reason is not None:
            self.hold()
            raise ExecutionAbortedError(reason, at_time_s=now - self._t0)

    # ------------------------------------------------------------------ identification
    def identify(self, duration: float = 2.0) -> DriveModel:
        """Learn each drive's lag and sag from a small swing around the current position
        (about 0.03 rad / 0.01 m), streamed like a trajectory."""
        start, _ = self.measure()
        self._bad_lines = self.client.bad_line_count
        amplitude = np.where(self.upper - self.lower > 0.5, 0.03, 0.01)
        _, commands = excitation(start, self.lower, self.upper, amplitude, duration)
        feedback = _Feedback(self.actuator, self.links)
        sent = self._stream(commands, feedback)
        self._settle_to(commands[-1], settle_timeout=1.0, feedback=None)
        n = feedback.complete()
        sample_times = np.array([feedback.sampled_at(i, n) for i in range(n)]) - sent[0]
        samples = np.array(feedback.values[:n])
        usable = sample_times >= 0
        self.drive = fit(sent - sent[0], commands, sample_times[usable], samples[usable])
        log.info("drive lags %s s, inertias %s s^2 (fit rms %s)", np.round(self.drive.lag, 3),
                 np.round(self.drive.inertia if self.drive.inertia is not None else 0.0, 4),
                 np.round(self.drive.residual, 5))
        return self.drive

    def _stream(self, commands: Array, feedback: _Feedback) -> Array:
        """Send rows of ``commands`` at the rate; return the send times (perf_counter)."""
        unsubscribe = self.client.subscribe(feedback)
        dt = 1.0 / self.options.rate_hz
        sent = np.empty(len(commands))
        old = sys.getswitchinterval()
        sys.setswitchinterval(0.0005)  # the embedded simulator shares the GIL: take turns often
        gc.disable()  # a collection pause would be a late command
        try:
            t0 = time.perf_counter()
            for k, u in enumerate(commands):
                _sleep_until(t0 + k * dt)
                sent[k] = time.perf_counter()
                self.send(u)
                self._holding = u
                self._check_feedback(feedback, t0)
        finally:
            gc.enable()
            sys.setswitchinterval(old)
            unsubscribe()
        return sent

    # ------------------------------------------------------------------ execution
    def execute(self, trajectory: Trajectory, goal: Array | None = None) -> ExecutionReport:
        """Stream ``trajectory``, then settle on ``goal`` (default: its last point).

        Raises:
            ExecutionAbortedError: the arm is not at the start, the tracking error or the
                feedback age passed its bound, the feedback was unreadable or not finite, the
                server sent a line that is not USARSim, the connection dropped, or Ctrl-C; the
                arm was told to hold where it is (when the connection still allows).
        """
        self._bad_lines = self.client.bad_line_count
        self._holding = None
        self._t0 = time.perf_counter()  # until the motion starts: identification, settling
        try:
            return self._execute(trajectory, goal)
        except KeyboardInterrupt:
            self.hold(self._holding)
            raise ExecutionAbortedError("interrupted (Ctrl-C)",
                                        at_time_s=time.perf_counter() - self._t0) from None
        except ConnectionLostError as exc:
            raise ExecutionAbortedError(f"the connection dropped: {exc}",
                                        at_time_s=time.perf_counter() - self._t0) from exc
        except (ResponseTimeoutError, ProtocolError) as exc:
            self.hold(self._holding)
            raise ExecutionAbortedError(f"the feedback failed: {exc}",
                                        at_time_s=time.perf_counter() - self._t0) from exc

    def _execute(self, trajectory: Trajectory, goal: Array | None) -> ExecutionReport:
        opts = self.options
        q_now, _ = self.measure(timeout=opts.feedback_timeout + 0.5)
        gap = np.abs(q_now - trajectory.q[0])
        if np.max(gap) > opts.start_tolerance:
            j = int(np.argmax(gap))
            raise ExecutionAbortedError(
                f"the arm is not at the trajectory's start (tolerance {opts.start_tolerance})",
                self.names[j], float(gap[j]), 0.0)
        if opts.feedforward and self.drive is None:
            self.identify()
        drive = self.drive if opts.feedforward and self.drive else DriveModel.none(len(q_now))
        feedback = _Feedback(self.actuator, self.links)
        unsubscribe = self.client.subscribe(feedback)
        dt = 1.0 / opts.rate_hz
        count = int(np.floor(trajectory.duration / dt)) + 1
        sends = np.empty(count)
        deadlines = np.empty(count)
        worst = np.zeros(len(q_now))
        checked = 0
        old = sys.getswitchinterval()
        sys.setswitchinterval(0.0005)
        gc.disable()
        t0 = self._t0 = time.perf_counter()
        try:
            for k in range(count):
                deadlines[k] = t0 + k * dt
                _sleep_until(deadlines[k])
                # Each target holds for dt (a zero-order hold): aim at the middle of its period.
                q, v = trajectory.at(k * dt + dt / 2)
                sends[k] = time.perf_counter()
                self.send(drive.command(q, v, trajectory.acceleration(k * dt + dt / 2)))
                self._holding = drive.command(q, np.zeros_like(v))
                checked = self._watch(trajectory, feedback, t0, checked, worst)
        finally:
            gc.enable()
            sys.setswitchinterval(old)
        goal = trajectory.q[-1] if goal is None else np.asarray(goal, float)
        try:
            settled, seconds = self._settle_to(goal, opts.settle_timeout, feedback,
                                               start=goal - drive.offset)
            self._watch(trajectory, feedback, t0, checked, worst)
        finally:
            unsubscribe()
        final, _ = self.measure(timeout=opts.feedback_timeout + 0.5)
        jitter = np.abs(sends - deadlines) * 1000
        n = feedback.complete()  # (a sample still arriving after unsubscribe is left out)
        sample_t = np.array([feedback.sampled_at(i, n) for i in range(n)]) - t0
        after_start = sample_t >= 0  # an ASTA taken just before the first command
        executed = ExecutedSamples(
            sample_t[after_start],
            np.array(feedback.values[:n]).reshape(-1, len(q_now))[after_start])
        return ExecutionReport(
            self.names, np.abs(final - goal), float(np.max(worst)), worst.copy(),
            (count - 1) / (sends[-1] - sends[0]) if count > 1 else 0.0,
            float(np.percentile(jitter, 50)), float(np.percentile(jitter, 99)),
            float(sends[-1] - t0), settled, seconds, goal, executed, started_at=t0)

    def _watch(self, trajectory: Trajectory, feedback: _Feedback, t0: float, checked: int,
               worst: Array) -> int:
        """Check the feedback and the ASTA samples that arrived since ``checked``; abort on a
        bound."""
        self._check_feedback(feedback, t0)
        n = feedback.complete()
        for i in range(checked, n):
            t = feedback.sampled_at(i, n) - t0
            if t < 0 or t > trajectory.duration:
                continue
            error = np.abs(feedback.values[i] - trajectory.at(t)[0])
            np.maximum(worst, error, out=worst)
            j = int(np.argmax(error))
            if error[j] > self.options.max_tracking_error:
                self.hold()
                raise ExecutionAbortedError(
                    f"tracking error above the bound {self.options.max_tracking_error}",
                    self.names[j], float(error[j]), t)
        return n

    def _settle_to(self, goal: Array, settle_timeout: float, feedback: _Feedback | None,
                   start: Array | None = None) -> tuple[bool, float]:
        """Hold ``goal``, nudging the target by the measured error (half of it per ASTA,
        bounded by ``correction_limit``), until two ASTAs in a row are within tolerance."""
        tol = self.options.settle_tolerance
        target = goal.copy() if start is None else start.copy()
        self.send(target)
        self._holding = target
        begin = time.perf_counter()
        good = 0
        after: float | None = None
        while time.perf_counter() - begin < settle_timeout:
            if feedback is not None:
                self._check_feedback(feedback, begin)
            q, after = self.measure(timeout=self.options.feedback_timeout + 0.5, after=after)
            error = q - goal
            good = good + 1 if np.max(np.abs(error)) <= tol else 0
            if good >= 2:
                return True, time.perf_counter() - begin
            target = np.clip(target - 0.5 * error, goal - self.options.correction_limit,
                             goal + self.options.correction_limit)
            self.send(target)
            self._holding = target
        return False, time.perf_counter() - begin

    def settle(self, goal: Array) -> tuple[bool, float]:
        """Bring the joints to ``goal`` (a small move) and settle there."""
        drive = self.drive or DriveModel.none(len(goal))
        return self._settle_to(np.asarray(goal, float), self.options.settle_timeout, None,
                               start=np.asarray(goal, float) - drive.offset)


def _sleep_until(deadline: float) -> None:
    """Sleep until ``deadline`` (perf_counter s): coarse sleep, then short yields."""
    remaining = deadline - time.perf_counter()
    if remaining > 0.001:
        time.sleep(remaining - 0.0008)
    while time.perf_counter() < deadline:
        time.sleep(0)
