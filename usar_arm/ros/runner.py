"""Runs checked trajectory goals on the arm, one at a time, with usar-arm's executor.

What ros2_control's joint_trajectory_controller does for its two interfaces: a newer goal
pre-empts the running one (which stops, the arm holding, and is aborted with that reason); a
cancel stops the motion and holds; path tolerances are checked against every ASTA while the
trajectory runs, goal tolerances after it has settled; a lost simulator or any executor abort
ends the goal with the executor's message. No ROS types here: the node passes callbacks.
Units: rad or m, s.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from usar_arm.control.executor import Executor
from usar_arm.core.errors import ExecutionAbortedError, UsarArmError
from usar_arm.core.spatial import Array
from usar_arm.ros.goals import (
    GOAL_TOLERANCE_VIOLATED,
    PATH_TOLERANCE_VIOLATED,
    SUCCESSFUL,
    CheckedGoal,
)
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient

log = logging.getLogger("usar_arm.ros")

Feedback = Callable[[Array, Array, Array], None]
"""Called per ASTA during a goal with (desired positions, desired velocities, actual
positions), the arm's joint order."""

TAKE_OVER_TIMEOUT_S = 10.0
"""The longest a new goal waits for the one it pre-empts to stop (s)."""


@dataclass
class Job:
    """One goal being run.

    Attributes:
        goal: the checked goal. cancelled: True once the client asked to cancel.
        feedback: where per-ASTA feedback goes. label: for logs.
    """

    goal: CheckedGoal
    cancelled: Callable[[], bool]
    feedback: Feedback
    label: str = "goal"
    ticket: int = 0
    """Its place in the order the goals arrived (:meth:`GoalRunner.ticket`): the newest wins."""
    preempted: str | None = None
    violation: str | None = None
    last_asta: float = field(default=-1.0)


@dataclass(frozen=True)
class Outcome:
    """How a goal ended: ``succeeded``, else aborted, or ``cancelled`` by its client, or
    ``preempted`` by a newer goal (ROS 2 reports that as aborted, ROS 1's actionlib as
    PREEMPTED); the FollowJointTrajectory error code and a message; ``state``: what the
    result reports besides (a GripperCommand's
    :class:`~usar_arm.ros.transport.GripperRecord`), None for none."""

    succeeded: bool
    code: int
    message: str
    cancelled: bool = False
    preempted: bool = False
    state: Any = None


class GoalRunner:
    """Executes jobs on an arm's executor, newest first.

    Args:
        executor: the arm's executor (its drive identified beforehand).
        client: the connection (for feedback and to notice a lost simulator).
        links: the USARSim link of each joint (ASTA order -> joint order).
    """

    def __init__(self, executor: Executor, client: UsarClient, actuator: str,
                 links: tuple[int, ...]):
        self.executor = executor
        self.client = client
        self.actuator = actuator
        self.links = links
        self._lock = threading.Lock()
        self._guard = threading.Lock()
        self._active: Job | None = None
        self._latest: Job | None = None
        self._tickets = 0
        self.stopping: str | None = None
        """Set when the node shuts down: the running goal stops with this reason."""

    def stop_active(self, reason: str) -> None:
        """Make the running job (if any) stop, the arm holding, with ``reason``."""
        with self._guard:
            if self._active is not None and self._active.preempted is None:
                self._active.preempted = reason

    def ticket(self) -> int:
        """The next number in arrival order (call it when a goal arrives)."""
        with self._guard:
            self._tickets += 1
            return self._tickets

    def wait_idle(self, timeout: float = TAKE_OVER_TIMEOUT_S) -> bool:
        """Wait (at most ``timeout`` s) until no job runs; False on timeout."""
        if not self._lock.acquire(timeout=timeout):
            return False
        self._lock.release()
        return True

    def run(self, job: Job) -> Outcome:
        """Pre-empt the running job, then execute ``job`` and say how it ended. Of several
        jobs waiting for the arm, only the newest (highest ticket) runs; the others end
        pre-empted."""
        with self._guard:
            if self._latest is not None and job.ticket < self._latest.ticket:
                return Outcome(False, SUCCESSFUL, "pre-empted by a newer goal before it "
                               "started", preempted=True)
            self._latest = job
        self.stop_active(f"pre-empted by a newer goal ({job.label})")
        if not self._lock.acquire(timeout=TAKE_OVER_TIMEOUT_S):
            return Outcome(False, PATH_TOLERANCE_VIOLATED, "the previous goal did not stop "
                           f"within {TAKE_OVER_TIMEOUT_S} s")
        try:
            with self._guard:
                if self._latest is not job:
                    return Outcome(False, SUCCESSFUL, "pre-empted by a newer goal before it "
                                   "started", preempted=True)
                self._active = job
            return self._run(job)
        finally:
            with self._guard:
                self._active = None
            self._lock.release()

    def _run(self, job: Job) -> Outcome:
        lost = self.client.closed_reason
        if lost is not None or not self.client.connected:
            return Outcome(False, PATH_TOLERANCE_VIOLATED,
                           f"the simulator connection is lost ({lost}); the goal was not run")
        end = time.monotonic() + job.goal.start_delay
        while time.monotonic() < end:  # a header stamp in the future: wait for it
            reason = self._stop_reason(job)
            if reason is not None:
                return self._stopped(job, reason)
            time.sleep(min(0.01, max(0.0, end - time.monotonic())))
        self.executor.monitor = lambda t: self._monitor(job, t)
        try:
            report = self.executor.execute(job.goal.trajectory)
        except ExecutionAbortedError as exc:
            return self._stopped(job, exc.reason, str(exc))
        except UsarArmError as exc:
            return Outcome(False, PATH_TOLERANCE_VIOLATED, str(exc))
        except Exception as exc:  # never the node's end: the goal reports it
            log.exception("goal failed")
            self.executor.hold()
            return Outcome(False, PATH_TOLERANCE_VIOLATED,
                           f"the execution failed: {type(exc).__name__}: {exc}")
        finally:
            self.executor.monitor = None
        final = report.goal + 0.0
        error = report.final_joint_error_rad
        bound = job.goal.goal_tolerance
        over = error > bound
        if np.any(over):
            j = int(np.argmax(np.where(over, error - bound, -np.inf)))
            name = self.executor.names[j]
            return Outcome(False, GOAL_TOLERANCE_VIOLATED, f"{name} ended {error[j]:.6f} from "
                           f"its goal {final[j]:.6f}, above its goal tolerance {bound[j]:g}"
                           f" (settled: {report.settled})")
        return Outcome(True, SUCCESSFUL, f"reached the goal in {report.duration_s:.2f} s "
                       f"(largest joint error {float(np.max(error)):.6f}, tracking "
                       f"{report.max_tracking_error_rad:.4f})")

    def _stop_reason(self, job: Job) -> str | None:
        if self.stopping is not None:
            return self.stopping
        if job.cancelled():
            return "cancelled by the client"
        return job.preempted

    def _stopped(self, job: Job, reason: str, detail: str = "") -> Outcome:
        """The outcome of a job that stopped before its end."""
        if job.cancelled() and reason == "cancelled by the client":
            return Outcome(False, SUCCESSFUL, "cancelled; the arm holds", cancelled=True)
        if job.violation is not None:
            return Outcome(False, PATH_TOLERANCE_VIOLATED, job.violation)
        return Outcome(False, PATH_TOLERANCE_VIOLATED if not job.preempted else SUCCESSFUL,
                       detail or f"{reason}; the arm holds",
                       preempted=job.preempted is not None and self.stopping is None)

    def _monitor(self, job: Job, t: float) -> str | None:
        """The executor's per-period question: stop? Also checks the path tolerance and
        sends feedback on each new ASTA."""
        reason = self._stop_reason(job)
        if reason is not None:
            return reason
        rec = self.client.latest("ASTA", self.actuator)
        if rec is None or rec.wall_time <= job.last_asta:
            return None
        job.last_asta = rec.wall_time
        joints = rec.message.joints(self.links) if isinstance(rec.message, m.Asta) else None
        if joints is None:
            return None
        actual = np.array(joints)
        sample_t = t - (time.perf_counter() - rec.wall_time)
        trajectory = job.goal.trajectory
        desired, velocity = trajectory.at(sample_t)
        job.feedback(desired, velocity, actual)
        if 0.0 <= sample_t <= trajectory.duration:
            error = np.abs(actual - desired)
            over = error > job.goal.path_tolerance
            if np.any(over):
                j = int(np.argmax(np.where(over, error, -np.inf)))
                job.violation = (f"{self.executor.names[j]} was {error[j]:.5f} off the path at "
                                 f"t = {sample_t:.2f} s, above its path tolerance "
                                 f"{job.goal.path_tolerance[j]:g}; the arm holds")
                return job.violation
        return None
