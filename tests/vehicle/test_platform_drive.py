"""cmd_vel -> wheel speeds (skid steering): the formula, and clamping that keeps direction and
ratio and never exceeds the limit; a NaN or infinite command is refused."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from usar_arm.core.errors import InvalidInputError
from usar_arm.ros.drive import wheel_speeds

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
