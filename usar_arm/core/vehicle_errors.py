"""The errors of describing and driving a ground vehicle: steering, commands, vehicle
parameters, waypoints.

A branch of the error tree of :mod:`usar_arm.core.errors`: the errors of the vehicles' own path
(``control/vehicle_wire.py``, ``control/drive_run.py``, the world file's scenery), which the
arm's pipeline never raises. Subclasses of :class:`~usar_arm.core.errors.InvalidInputError`
(exit code 65) and, for a steering usar-arm cannot describe, of
:class:`~usar_arm.core.errors.DescriptionError`; each carries its evidence as attributes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from usar_arm.core.errors import DescriptionError, InvalidInputError


class UnsupportedSteeringError(DescriptionError):
    """A ground vehicle whose steering usar-arm cannot describe or drive (the message names its
    steering type and the supported ones)."""


@dataclass(eq=False, repr=False)
class NonFiniteCommandError(InvalidInputError):
    """A velocity command (or a vehicle parameter it is mapped with) is NaN or infinite.

    Attributes:
        values: name -> the value given (m/s, rad/s, m), every one that was checked.
    """

    values: dict[str, float]

    def message(self) -> str:
        """This error's text, from its evidence."""
        bad = ", ".join(f"{k} = {v}" for k, v in self.values.items() if not math.isfinite(v))
        return f"a drive command needs finite numbers; got {bad}"


@dataclass(eq=False, repr=False)
class VehicleParameterError(InvalidInputError):
    """A vehicle parameter (wheel radius, separation, maximum wheel speed) is not positive.

    Attributes:
        name: the parameter. value: what it was (m or rad/s).
    """

    name: str
    value: float

    def message(self) -> str:
        """This error's text, from its evidence."""
        return f"the vehicle's {self.name} must be a positive number, got {self.value}"


@dataclass(eq=False, repr=False)
class NotAVehicleError(InvalidInputError):
    """The spawned robot is no ground vehicle (its CONF {Type Robot} says what it is instead):
    it can be neither described as a platform nor driven.

    Attributes:
        robot: the class asked for. platform_type: what the robot's CONF says it is.
    """

    robot: str
    platform_type: str

    def message(self) -> str:
        """This error's text, from its evidence."""
        return (f"{self.robot} is a {self.platform_type}, not a ground vehicle: describe an "
                "arm with usar-arm urdf; usar-arm drives ground vehicles such as "
                "USARBot.P3AT and USARBot.FrontAckerman")


@dataclass(eq=False, repr=False)
class OutsideWorldError(InvalidInputError):
    """A waypoint lies outside the world's walls or inside one of its boxes.

    Attributes:
        index: the waypoint's 1-based position. point: its x, y (m, map frame).
        where: what it is outside of, or inside.
    """

    index: int
    point: tuple[float, float]
    where: str

    def message(self) -> str:
        """This error's text, from its evidence."""
        return (f"waypoint {self.index} ({self.point[0]:g}, {self.point[1]:g}) m lies "
                f"{self.where}")
