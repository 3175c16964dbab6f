"""Timing and execution: a planned, timed motion (:mod:`.motion`), Ruckig timing
(:mod:`.timing`), trajectories and their limit checks (:mod:`.trajectory`), and the streaming
executor (:mod:`.executor`: ACT out at 100 Hz, ASTA in, drive feedforward, settling, tip-sensor
correction)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.control.ackermann import AckermannCommand as AckermannCommand
    from usar_arm.control.ackermann import ackermann_command as ackermann_command
    from usar_arm.control.executor import ExecutionOptions as ExecutionOptions
    from usar_arm.control.executor import ExecutionReport as ExecutionReport
    from usar_arm.control.executor import Executor as Executor
    from usar_arm.control.motion import MotionOptions as MotionOptions
    from usar_arm.control.motion import MotionPlan as MotionPlan
    from usar_arm.control.motion import plan_motion as plan_motion
    from usar_arm.control.skid import WheelSpeeds as WheelSpeeds
    from usar_arm.control.skid import wheel_speeds as wheel_speeds
    from usar_arm.control.timing import TimedMotion as TimedMotion
    from usar_arm.control.tip import TipReading as TipReading
    from usar_arm.control.tip import TipSensor as TipSensor
    from usar_arm.control.trajectory import LimitReport as LimitReport
    from usar_arm.control.trajectory import MotionLimits as MotionLimits
    from usar_arm.control.trajectory import Trajectory as Trajectory
    from usar_arm.control.trajectory import check_limits as check_limits

__getattr__, __dir__, __all__ = exports(__name__, __file__)
