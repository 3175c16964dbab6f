"""The skid-steer mapping: body velocity -> wheel spins, clamped keeping the ratio."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from usar_arm.control.skid import body_velocity, wheel_speeds
from usar_arm.core.vehicle_errors import NonFiniteCommandError, VehicleParameterError

P3AT = {"radius": 0.098, "separation": 0.36, "max_speed": 1.2999}
speeds = st.floats(-5.0, 5.0, allow_nan=False)


def test_a_clamped_pair_never_rounds_above_the_limit() -> None:
    """0.5 m/s straight: x * (max / |x|) is 1.2999000000000003 in floating point."""
    left, right, clamped = wheel_speeds(0.5, 0.0, **P3AT)
    assert clamped and left == right == P3AT["max_speed"]


def test_standing_still_spins_no_wheel() -> None:
    assert wheel_speeds(0.0, 0.0, **P3AT) == (0.0, 0.0, False)


def test_a_slow_straight_run_spins_both_sides_alike_unclamped() -> None:
    left, right, clamped = wheel_speeds(0.1, 0.0, **P3AT)
    assert left == pytest.approx(0.1 / 0.098) and right == pytest.approx(left)
    assert not clamped


def test_turning_left_spins_the_right_side_faster() -> None:
    left, right, _ = wheel_speeds(0.0, 0.5, **P3AT)
    assert right == pytest.approx(0.5 * 0.18 / 0.098) and left == pytest.approx(-right)


@given(speeds, speeds)
def test_clamping_keeps_direction_and_ratio_and_never_exceeds_the_max(v: float, w: float
                                                                      ) -> None:
    left, right, clamped = wheel_speeds(v, w, **P3AT)
    raw_left = (v - w * 0.18) / 0.098
    raw_right = (v + w * 0.18) / 0.098
    assert max(abs(left), abs(right)) <= P3AT["max_speed"]  # exactly: what DRIVE may send
    assert clamped == (max(abs(raw_left), abs(raw_right)) > P3AT["max_speed"])
    # same direction: the clamped pair is a positive multiple of the raw pair
    assert math.copysign(1, left) == math.copysign(1, raw_left) or raw_left == 0
    assert math.copysign(1, right) == math.copysign(1, raw_right) or raw_right == 0
    assert left * raw_right == pytest.approx(right * raw_left, abs=1e-9)
    if not clamped:
        assert (left, right) == pytest.approx((raw_left, raw_right))


@given(speeds, speeds)
def test_an_unclamped_command_maps_back_to_itself(v: float, w: float) -> None:
    left, right, clamped = wheel_speeds(v, w, 0.098, 0.36, 1e6)
    assert not clamped
    assert body_velocity(left, right, 0.098, 0.36) == pytest.approx((v, w), abs=1e-9)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("field", ["v", "w", "radius", "separation", "max_speed"])
def test_nan_and_inf_are_refused_naming_the_value(bad: float, field: str) -> None:
    args = {"v": 0.1, "w": 0.1, **P3AT, field: bad}
    with pytest.raises(NonFiniteCommandError, match=f"{field} = ") as info:
        wheel_speeds(**args)
    assert math.isnan(info.value.values[field]) or math.isinf(info.value.values[field])


@pytest.mark.parametrize("field", ["radius", "separation", "max_speed"])
def test_a_vehicle_parameter_that_is_not_positive_is_refused(field: str) -> None:
    with pytest.raises(VehicleParameterError, match=field):
        wheel_speeds(0.1, 0.0, **{**P3AT, field: 0.0})
