"""The Ackermann mapping: body velocity -> wheel spin and front steer (bicycle model)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from usar_arm.control.ackermann import ackermann_command, yaw_rate
from usar_arm.core.vehicle_errors import NonFiniteCommandError, VehicleParameterError

# FrontAckerman's numbers as its CONF/GEO print them (docs/protocol.md section 10)
CAR = {"radius": 0.128, "wheel_base": 0.956, "max_speed": 0.56, "max_steer": 0.5}
speeds = st.floats(-2.0, 2.0, allow_nan=False)
steers = st.floats(-0.5, 0.5, allow_nan=False)


def test_straight_ahead_spins_the_wheels_without_steering() -> None:
    cmd = ackermann_command(0.05, 0.0, **CAR)
    assert cmd.speed == pytest.approx(0.05 / 0.128) and cmd.steer == 0.0
    assert not (cmd.speed_clamped or cmd.steer_clamped or cmd.turn_refused)
    assert cmd.moving and cmd.wire_steer == 0.0 and math.copysign(1, cmd.wire_steer) == 1


def test_a_left_turn_steers_left_and_the_wire_sees_it_negated() -> None:
    cmd = ackermann_command(0.05, 0.02, **CAR)
    assert cmd.steer == pytest.approx(math.atan(0.02 * 0.956 / 0.05)) and cmd.steer > 0
    assert cmd.wire_steer == -cmd.steer  # USARSim's z down: positive FrontSteer turns right


def test_a_turn_on_the_spot_is_refused_keeping_the_steer_and_standing_still() -> None:
    cmd = ackermann_command(0.0, 0.7, **CAR, previous_steer=-0.2)
    assert cmd.turn_refused and cmd.speed == 0.0 and cmd.steer == -0.2 and not cmd.moving
    still = ackermann_command(0.0, 0.0, **CAR, previous_steer=0.1)
    assert not still.turn_refused and still.steer == 0.1


def test_a_sharp_turn_is_cut_to_the_largest_steer_and_a_fast_one_to_the_largest_spin() -> None:
    sharp = ackermann_command(0.05, 5.0, **CAR)
    assert sharp.steer == 0.5 and sharp.steer_clamped and not sharp.speed_clamped
    fast = ackermann_command(-1.0, 0.0, **CAR)
    assert fast.speed == -0.56 and fast.speed_clamped and not fast.steer_clamped


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_commands_are_refused_naming_the_value(bad: float) -> None:
    with pytest.raises(NonFiniteCommandError, match=r"v = (nan|inf|-inf)") as info:
        ackermann_command(bad, 0.0, **CAR)
    assert math.isnan(info.value.values["v"]) or math.isinf(info.value.values["v"])
    with pytest.raises(NonFiniteCommandError):
        ackermann_command(0.1, bad, **CAR)


@pytest.mark.parametrize("name", ["radius", "wheel_base", "max_speed", "max_steer"])
def test_a_vehicle_parameter_that_is_not_positive_is_refused(name: str) -> None:
    with pytest.raises(VehicleParameterError, match=name):
        ackermann_command(0.1, 0.1, **(CAR | {name: 0.0}))


@given(speeds, speeds, steers)
def test_the_command_never_exceeds_the_limits_and_keeps_the_turns_sense(
        v: float, w: float, previous: float) -> None:
    cmd = ackermann_command(v, w, **CAR, previous_steer=previous)
    assert abs(cmd.speed) <= CAR["max_speed"] and abs(cmd.steer) <= CAR["max_steer"]
    if v == 0.0:
        assert cmd.speed == 0.0 and cmd.steer == previous and cmd.turn_refused == (w != 0.0)
        return
    assert math.copysign(1, cmd.speed) == math.copysign(1, v)
    if w == 0.0:
        assert cmd.steer == 0.0
    elif cmd.steer != 0.0:  # (a tiny turn may underflow to no steer at all)
        assert (cmd.steer > 0) == ((w > 0) == (v > 0))  # turns as asked
    assert cmd.speed_clamped == (abs(v / CAR["radius"]) > CAR["max_speed"])


@given(st.floats(0.01, 0.07), st.floats(-0.03, 0.03))
def test_an_unclamped_command_drives_the_yaw_rate_asked(v: float, w: float) -> None:
    cmd = ackermann_command(v, w, **CAR)
    if cmd.steer_clamped:  # (curvatures beyond tan(0.5) / 0.956 m: wider, same sense)
        assert abs(yaw_rate(cmd.speed, cmd.steer, 0.128, 0.956)) < abs(w)
        return
    assert yaw_rate(cmd.speed, cmd.steer, 0.128, 0.956) == pytest.approx(w, abs=1e-12)
    assert cmd.speed * 0.128 == pytest.approx(v)
