"""Timing and execution: a planned, timed motion (:mod:`.motion`), Ruckig timing
(:mod:`.timing`), trajectories and their limit checks (:mod:`.trajectory`), and the streaming
executor (:mod:`.executor`: ACT out at 100 Hz, ASTA in, drive feedforward, settling, tip-sensor
correction)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.control.ackermann import AckermannCommand, ackermann_command
    from usar_arm.control.executor import ExecutionOptions, ExecutionReport, Executor
    from usar_arm.control.motion import MotionOptions, MotionPlan, plan_motion
    from usar_arm.control.skid import WheelSpeeds, wheel_speeds
    from usar_arm.control.timing import TimedMotion
    from usar_arm.control.tip import TipReading, TipSensor
    from usar_arm.control.trajectory import LimitReport, MotionLimits, Trajectory, check_limits

_HOMES = {
    "ackermann": ("AckermannCommand", "ackermann_command"),
    "executor": ("ExecutionOptions", "ExecutionReport", "Executor"),
    "motion": ("MotionOptions", "MotionPlan", "plan_motion"),
    "skid": ("WheelSpeeds", "wheel_speeds"),
    "timing": ("TimedMotion",),
    "tip": ("TipReading", "TipSensor"),
    "trajectory": ("LimitReport", "MotionLimits", "Trajectory", "check_limits"),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["AckermannCommand", "ExecutionOptions", "ExecutionReport", "Executor", "LimitReport",
           "MotionLimits", "MotionOptions", "MotionPlan", "TimedMotion", "TipReading", "TipSensor",
           "Trajectory", "WheelSpeeds", "ackermann_command", "check_limits", "plan_motion",
           "wheel_speeds"]

__getattr__ = exports(__name__, _HOMES)
