"""cmd_vel -> wheel speeds for a skid-steered vehicle (plain Python, no ROS types).

A body velocity ``v`` (m/s, forward) and yaw rate ``w`` (rad/s, counter-clockwise, REP-103) need
the left and right wheels to spin at (rad/s, positive forward)::

    left  = (v - w * separation / 2) / radius
    right = (v + w * separation / 2) / radius

When either exceeds the wheels' limit both are scaled by the same factor, so the robot keeps its
direction and its turning radius and goes as fast as it can. A NaN or infinite command is refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from usar_arm.core.errors import InvalidInputError


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
        InvalidInputError: ``v`` or ``w`` is NaN or infinite (the caller stops the robot).
    """
    if not (math.isfinite(v) and math.isfinite(w)):
        raise InvalidInputError(f"cmd_vel linear.x {v} and angular.z {w} must be finite "
                                "numbers (m/s, rad/s)")
    left = (v - w * separation / 2.0) / radius
    right = (v + w * separation / 2.0) / radius
    fastest = max(abs(left), abs(right))
    scale = 1.0 if fastest <= max_speed else max_speed / fastest
    return WheelCommand(left * scale + 0.0, right * scale + 0.0, scale, (left, right))
