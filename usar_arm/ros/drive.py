"""cmd_vel -> DRIVE, as the platform node sends it: wheel speeds for a skid-steered vehicle, a
spin and a front steer for an Ackermann one (:func:`velocity_command` picks by the
description's steering type).

For a skid-steered vehicle the mapping is :func:`usar_arm.control.skid.wheel_speeds` (the
one ``usar-arm drive`` uses): both wheels scaled by the same factor when one exceeds the
limit, a NaN or infinite command refused. This module adds what the node logs and decides
with: the speeds asked before the scaling, and whether the command moves the robot at all. For
an Ackermann vehicle it is :func:`usar_arm.control.ackermann.ackermann_command`, the one
``usar-arm drive`` uses too.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

from usar_arm.control.ackermann import AckermannCommand, ackermann_command, drive_message
from usar_arm.control.skid import wheel_speeds as skid_wheel_speeds
from usar_arm.core.platform import PlatformDescription
from usar_arm.usarsim import messages as m


@dataclass(frozen=True)
class WheelCommand:
    """Spin speeds of the left and right wheels (rad/s, positive forward).

    Attributes:
        scale: the factor the asked speeds were multiplied by to stay within the limit (1: not
        clamped). asked: the speeds before clamping (rad/s).
    """

    left: float
    right: float
    scale: float = 1.0
    asked: tuple[float, float] = (0.0, 0.0)

    @property
    def clamped(self) -> bool:
        """Whether the command was slowed down to the limit."""
        return self.scale < 1.0

    @property
    def moving(self) -> bool:
        """Whether any wheel is asked to turn."""
        return self.left != 0.0 or self.right != 0.0


STOP = WheelCommand(0.0, 0.0)


def wheel_speeds(v: float, w: float, radius: float, separation: float, max_speed: float
                 ) -> WheelCommand:
    """The wheel speeds for body velocity ``v`` (m/s) and yaw rate ``w`` (rad/s) on wheels of
    ``radius`` (m) ``separation`` (m) apart, at most ``max_speed`` (rad/s) each.

    Raises:
        NonFiniteCommandError: ``v`` or ``w`` is NaN or infinite (the caller stops the robot);
            an :class:`~usar_arm.core.errors.InvalidInputError`.
    """
    asked = skid_wheel_speeds(v, w, radius, separation, sys.float_info.max)  # never scaled
    spins = skid_wheel_speeds(v, w, radius, separation, max_speed)
    fastest = max(abs(asked.left), abs(asked.right))
    scale = max_speed / fastest if spins.clamped else 1.0
    return WheelCommand(spins.left + 0.0, spins.right + 0.0,  # no -0.0 on the wire
                        scale, (asked.left, asked.right))


DriveCommand = WheelCommand | AckermannCommand
"""What the node sends: a skid-steered vehicle's two spins, or an Ackermann vehicle's spin and
front steer (:mod:`usar_arm.control.ackermann`)."""


def velocity_command(desc: PlatformDescription, v: float, w: float, current: DriveCommand
                     ) -> DriveCommand:
    """The command for ``cmd_vel`` (``v`` m/s, ``w`` rad/s) by the vehicle's steering type; an
    Ackermann vehicle keeps ``current``'s steer when asked to turn without moving.

    Raises:
        NonFiniteCommandError: ``v`` or ``w`` is NaN or infinite.
    """
    if not desc.ackermann:
        return wheel_speeds(v, w, desc.wheel_radius, desc.wheel_separation, desc.max_speed)
    steer = current.steer if isinstance(current, AckermannCommand) else 0.0
    return ackermann_command(v, w, desc.wheel_radius, desc.wheel_base, desc.max_speed,
                             desc.max_front_steer, steer)


def stop_command(desc: PlatformDescription, current: DriveCommand) -> DriveCommand:
    """Standing still: no spin (an Ackermann vehicle keeps its steer)."""
    if isinstance(current, AckermannCommand):
        return current._replace(speed=0.0, speed_clamped=False, steer_clamped=False,
                                turn_refused=False)
    return AckermannCommand(0.0, 0.0) if desc.ackermann else STOP


def drive_line(command: DriveCommand) -> m.Drive:
    """The DRIVE line of a command (rad/s and rad, not normalized)."""
    if isinstance(command, AckermannCommand):
        return drive_message(command)
    return m.Drive(command.left, command.right, normalized=False)
