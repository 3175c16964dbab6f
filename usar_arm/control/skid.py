"""Body velocity -> wheel spin speeds of a skid-steered vehicle (the P3AT's DRIVE command).

A skid-steered vehicle turns by driving its two sides at different speeds. For a forward speed
``v`` (m/s) and a yaw rate ``w`` (rad/s, positive counter-clockwise seen from above, REP-103)
the wheels of each side spin at

    left = (v - w * separation / 2) / radius,   right = (v + w * separation / 2) / radius   (rad/s)

A pair beyond the vehicle's maximum spin is scaled down together, so the ratio (and with it the
radius of the turn) is kept and only the speed along the arc drops. Pure: no wire, no state.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from usar_arm.core.vehicle_errors import NonFiniteCommandError, VehicleParameterError


class WheelSpeeds(NamedTuple):
    """Spin speeds of the left and right wheels (rad/s, positive forward) and whether they were
    scaled down to the vehicle's maximum."""

    left: float
    right: float
    clamped: bool


def wheel_speeds(v: float, w: float, radius: float, separation: float,
                 max_speed: float) -> WheelSpeeds:
    """The wheel spins (rad/s) that drive the vehicle at ``v`` (m/s) and ``w`` (rad/s).

    Args:
        v: forward speed (m/s). w: yaw rate (rad/s, counter-clockwise positive, z up).
        radius: wheel radius (m). separation: distance between the left and right wheels (m).
        max_speed: largest wheel spin the vehicle honours (rad/s).

    Returns:
        The spins; when one exceeds ``max_speed`` both are multiplied by the same factor so the
        larger equals ``max_speed`` (``clamped`` is then True).

    Raises:
        NonFiniteCommandError: any argument is NaN or infinite.
        VehicleParameterError: radius, separation or max_speed is not positive.
    """
    given = {"v": v, "w": w, "radius": radius, "separation": separation,
             "max_speed": max_speed}
    if not all(math.isfinite(x) for x in given.values()):
        raise NonFiniteCommandError(given)
    for name in ("radius", "separation", "max_speed"):
        if given[name] <= 0:
            raise VehicleParameterError(name, given[name])
    left = (v - w * separation / 2) / radius
    right = (v + w * separation / 2) / radius
    largest = max(abs(left), abs(right))
    if largest <= max_speed:
        return WheelSpeeds(left, right, False)
    scale = max_speed / largest
    # (the larger spin is set to the limit exactly: x * (max / |x|) may round above it)
    return WheelSpeeds(_at_most(left * scale, max_speed), _at_most(right * scale, max_speed),
                       True)


def _at_most(spin: float, limit: float) -> float:
    return math.copysign(min(abs(spin), limit), spin)


def body_velocity(left: float, right: float, radius: float,
                  separation: float) -> tuple[float, float]:
    """The inverse: forward speed (m/s) and yaw rate (rad/s) of wheel spins (rad/s)."""
    return radius * (left + right) / 2, radius * (right - left) / separation
