"""Body velocity -> wheel spin and steer angle of an Ackermann-steered vehicle (its DRIVE).

An Ackermann vehicle (UDK's ``AckermanSteeredVehicle``, docs/protocol.md section 10) cannot
turn on the spot: it rolls along arcs whose curvature its front steer sets. In the bicycle
model about the rear axle, a forward speed ``v`` (m/s) with yaw rate ``w`` (rad/s, positive
counter-clockwise seen from above, REP-103) needs the steer

    steer = atan(w * wheel_base / v)          (rad, positive to the left)

and every wheel spinning at ``v / radius`` (rad/s). The steer is clamped to the vehicle's
largest angle and the spin to its largest wheel speed, each on its own (a clamped steer makes
the turn wider, a clamped spin the vehicle slower along the same arc). A turn asked with
``v = 0`` cannot be driven: the vehicle stands still and keeps its steer, and the command says
so (:attr:`AckermannCommand.turn_refused`). Pure: no wire, no state; :func:`drive_message`
gives the DRIVE line to send.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from usar_arm.core.vehicle_errors import NonFiniteCommandError, VehicleParameterError
from usar_arm.usarsim import messages as m


class AckermannCommand(NamedTuple):
    """What to send: the wheels' spin and the front steer, and what had to give way.

    Attributes:
        speed: spin of every driven wheel (rad/s, positive forward): DRIVE's ``Speed``.
        steer: front steer angle (rad, REP-103: positive turns left).
        speed_clamped: the spin asked exceeded the vehicle's maximum and was cut to it.
        steer_clamped: the steer asked exceeded the vehicle's largest angle and was cut to it.
        turn_refused: a yaw rate was asked without a forward speed (not drivable).
    """

    speed: float
    steer: float
    speed_clamped: bool = False
    steer_clamped: bool = False
    turn_refused: bool = False

    @property
    def wire_steer(self) -> float:
        """The steer as DRIVE's ``FrontSteer`` carries it (rad, USARSim frame: z down, so a
        positive angle turns right): the REP-103 steer negated."""
        return -self.steer + 0.0  # (no -0.0 on the wire)

    @property
    def moving(self) -> bool:
        """Whether the wheels are asked to turn."""
        return self.speed != 0.0


def ackermann_command(v: float, w: float, radius: float, wheel_base: float, max_speed: float,
                      max_steer: float, previous_steer: float = 0.0) -> AckermannCommand:
    """The wheel spin and front steer that drive the vehicle at ``v`` (m/s) and ``w`` (rad/s).

    Args:
        v: forward speed (m/s) of the rear axle's centre. w: yaw rate (rad/s, z up).
        radius: wheel radius (m). wheel_base: front to rear axle (m).
        max_speed: largest wheel spin the vehicle honours (rad/s, CONF MaxSpeed).
        max_steer: largest steer angle either way (rad; half of CONF MaxFrontSteer, which is
            the steer joints' range).
        previous_steer: the steer in force (rad, REP-103), kept when no speed is asked.

    Raises:
        NonFiniteCommandError: any argument is NaN or infinite.
        VehicleParameterError: radius, wheel_base, max_speed or max_steer is not positive.
    """
    given = {"v": v, "w": w, "radius": radius, "wheel_base": wheel_base,
             "max_speed": max_speed, "max_steer": max_steer, "previous_steer": previous_steer}
    if not all(math.isfinite(x) for x in given.values()):
        raise NonFiniteCommandError(given)
    for name in ("radius", "wheel_base", "max_speed", "max_steer"):
        if given[name] <= 0:
            raise VehicleParameterError(name, given[name])
    kept = _within(previous_steer, max_steer)
    if v == 0.0:
        return AckermannCommand(0.0, kept, steer_clamped=kept != previous_steer,
                                turn_refused=w != 0.0)
    asked_steer = math.atan(w * wheel_base / v)
    steer = _within(asked_steer, max_steer)
    asked_speed = v / radius
    speed = _within(asked_speed, max_speed)
    return AckermannCommand(speed + 0.0, steer + 0.0, speed != asked_speed,
                            steer != asked_steer)


def _within(value: float, limit: float) -> float:
    return math.copysign(min(abs(value), limit), value)


def yaw_rate(speed: float, steer: float, radius: float, wheel_base: float) -> float:
    """The inverse: the yaw rate (rad/s) of wheels spinning at ``speed`` (rad/s) with the front
    steer ``steer`` (rad, REP-103), bicycle model about the rear axle."""
    return speed * radius * math.tan(steer) / wheel_base


def drive_message(command: AckermannCommand) -> m.Drive:
    """The DRIVE line of a command: ``{Speed s} {FrontSteer a} {RearSteer 0}`` (rad/s, rad in
    the USARSim frame), not normalized; UDK acts only when all three are given."""
    return m.Drive(normalized=False, speed=command.speed, front_steer=command.wire_steer,
                   rear_steer=0.0)
