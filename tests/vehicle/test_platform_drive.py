"""cmd_vel -> wheel speeds (skid steering): the formula, and clamping that keeps direction and
ratio and never exceeds the limit; a NaN or infinite command is refused; an Ackermann vehicle
gets its spin and steer instead."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from usar_arm.control.ackermann import AckermannCommand
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.platform import PlatformDescription
from usar_arm.ros.drive import (
    STOP,
    WheelCommand,
    drive_line,
    stop_command,
    velocity_command,
    wheel_speeds,
)
from usar_arm.usarsim import messages as m

RADIUS, SEPARATION, LIMIT = 0.098, 0.36, 1.2999
speeds = st.floats(-5.0, 5.0, allow_nan=False)


def test_within_the_limit_the_formula_holds() -> None:
    cmd = wheel_speeds(0.05, 0.2, RADIUS, SEPARATION, LIMIT)
    assert cmd.left == pytest.approx((0.05 - 0.2 * 0.18) / RADIUS)
    assert cmd.right == pytest.approx((0.05 + 0.2 * 0.18) / RADIUS)
    assert not cmd.clamped and cmd.scale == 1.0


@given(speeds, speeds)
def test_clamping_keeps_direction_and_ratio_and_never_exceeds_the_limit(v: float, w: float
                                                                        ) -> None:
    cmd = wheel_speeds(v, w, RADIUS, SEPARATION, LIMIT)
    left, right = cmd.asked
    assert max(abs(cmd.left), abs(cmd.right)) <= LIMIT
    assert math.copysign(1, cmd.left) == math.copysign(1, left) or cmd.left == left == 0
    assert math.copysign(1, cmd.right) == math.copysign(1, right) or cmd.right == right == 0
    assert cmd.left * right == pytest.approx(cmd.right * left, abs=1e-9)  # same ratio
    if max(abs(left), abs(right)) > LIMIT:
        assert cmd.clamped and max(abs(cmd.left), abs(cmd.right)) == pytest.approx(LIMIT)
    else:
        assert (cmd.left, cmd.right) == (left, right)


@pytest.mark.parametrize("v, w", [(math.nan, 0.0), (0.0, math.inf), (-math.inf, math.nan)])
def test_a_command_that_is_not_finite_is_refused(v: float, w: float) -> None:
    with pytest.raises(InvalidInputError, match="needs finite numbers"):
        wheel_speeds(v, w, RADIUS, SEPARATION, LIMIT)


def _vehicle(steering: str) -> PlatformDescription:
    return PlatformDescription(
        name="V", robot_class="USARBot.V", platform_type="GroundVehicle",
        steering_type=steering, mass=1.0, max_speed=0.56, max_torque=1.0, wheel_radius=0.128,
        wheel_separation=0.452, wheel_base=0.956, dimensions=(0.956, 0.452, 0.0),
        axle_height=0.0, wheels=(), sensors=(), max_front_steer=0.5)


def test_the_node_maps_cmd_vel_by_the_steering_type() -> None:
    skid = velocity_command(_vehicle("SkidSteered"), 0.05, 0.1, STOP)
    assert isinstance(skid, WheelCommand) and skid.right > skid.left
    assert drive_line(skid) == m.Drive(skid.left, skid.right, normalized=False)
    car = _vehicle("AckermanSteered")
    turn = velocity_command(car, 0.05, 0.02, stop_command(car, STOP))
    assert isinstance(turn, AckermannCommand)
    assert turn.steer == pytest.approx(math.atan(0.02 * 0.956 / 0.05))
    line = drive_line(turn)
    assert (line.speed, line.front_steer, line.rear_steer, line.left) == (
        pytest.approx(0.05 / 0.128), -turn.steer, 0.0, None)
    spot = velocity_command(car, 0.0, 0.5, turn)  # no speed: stands, keeps the steer
    assert isinstance(spot, AckermannCommand) and spot.turn_refused and not spot.moving
    assert spot.steer == turn.steer
    stopped = stop_command(car, turn)
    assert stopped == AckermannCommand(0.0, turn.steer) and drive_line(stopped).speed == 0.0
    with pytest.raises(InvalidInputError, match="needs finite numbers"):
        velocity_command(car, math.nan, 0.0, turn)
