"""Pure pursuit on an ideal unicycle: it follows a loop back to where it began, turns on the
spot toward a point behind it, and stops within the goal tolerance."""

from __future__ import annotations

import math

import pytest

from usar_arm.control.pursuit import PurePursuit, PursuitOptions, Segment, script_command
from usar_arm.core.errors import InvalidInputError


def _drive(pursuit: PurePursuit, pose: tuple[float, float, float], dt: float = 0.05,
           steps: int = 20000) -> list[tuple[float, float, float]]:
    """Integrate an ideal unicycle under the pursuit's commands until it is done."""
    path = [pose]
    for _ in range(steps):
        v, w = pursuit.command(*pose)
        if pursuit.done:
            return path
        x, y, yaw = pose
        pose = (x + v * math.cos(yaw) * dt, y + v * math.sin(yaw) * dt, yaw + w * dt)
        path.append(pose)
    raise AssertionError(f"not done after {steps} steps; at {pose}")


def test_a_closed_loop_is_driven_round_and_ends_where_it_began() -> None:
    square = [(5, 0), (5, 5), (0, 5), (0, 0)]
    pursuit = PurePursuit((0, 0), square, PursuitOptions(goal_tolerance_m=0.05))
    path = _drive(pursuit, (0.0, 0.0, 0.0))
    assert math.dist(path[-1][:2], (0, 0)) <= 0.05
    for corner in square[:3]:  # it went round: near every corner on the way
        assert min(math.dist(p[:2], corner) for p in path) < 0.5
    assert pursuit.length_m == pytest.approx(20.0)


def test_a_point_behind_is_faced_by_turning_on_the_spot() -> None:
    pursuit = PurePursuit((0, 0), [(-2, 0)], PursuitOptions(turn_rate_rps=0.7))
    assert pursuit.command(0.0, 0.0, 0.0) == (0.0, pytest.approx(0.7))
    path = _drive(pursuit, (0.0, 0.0, 0.0))
    assert math.dist(path[-1][:2], (-2, 0)) <= 0.1


def test_a_point_ahead_and_left_is_reached_on_a_left_arc() -> None:
    pursuit = PurePursuit((0, 0), [(3, 1)], PursuitOptions())
    v, w = pursuit.command(0.0, 0.0, 0.2)
    assert v > 0 and w > 0
    assert all(p[1] >= -1e-9 for p in _drive(pursuit, (0.0, 0.0, 0.2)))


@pytest.mark.parametrize("field", ["lookahead_m", "max_speed_mps", "goal_tolerance_m",
                                   "turn_rate_rps", "turn_in_place_rad"])
@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf])
def test_options_must_be_positive_numbers(field: str, bad: float) -> None:
    with pytest.raises(InvalidInputError, match=field):
        PursuitOptions(**{field: bad})


def test_a_script_holds_each_segment_for_its_duration_then_ends() -> None:
    script = [Segment(1.0, 0.1, 0.0), Segment(2.0, 0.0, 0.5)]
    assert script_command(script, 0.0) == (0.1, 0.0)
    assert script_command(script, 1.5) == (0.0, 0.5)
    assert script_command(script, 3.0) is None
