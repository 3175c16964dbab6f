"""cmd_vel -> wheel speeds for a skid-steered vehicle, as the platform node sends them.

The mapping is :func:`usar_arm.control.skid.wheel_speeds` (the one ``usar-arm drive`` uses):
both wheels scaled by the same factor when one exceeds the limit, a NaN or infinite command
refused. This module adds what the node logs and decides with: the speeds asked before the
scaling, and whether the command moves the robot at all.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

from usar_arm.control.skid import wheel_speeds as skid_wheel_speeds


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
