"""Blended motions keep every limit between their samples and where their segments meet.

The judge is the planning re-check's finite-difference test (positions only, every 1 ms: the
first, second and third differences may not exceed the velocity, acceleration and jerk limits)
and an exact position-limit test on those samples. Two defects it caught: Ruckig ends a
segment within ~1e-8 of its target, so the motion jumped that much where the next segment
began (a third difference of gap / h^3, up to 1.1x the jerk limit); and a pass through a
waypoint on a joint limit overshot it by ~1e-7 rad between the 5 ms samples the blend checked.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.planning.recheck import finite_difference_violations
from usar_arm.control.timing import blended
from usar_arm.control.trajectory import MotionLimits
from usar_arm.planning.robot import Robot, robot_from_files

ROOT = Path(__file__).resolve().parents[2]

ON_A_LIMIT = np.array([
    [2.4444580369514726, 0.26921442422198005, 2.7172861874766903, 2.56714309332007,
     0.4836055250651765, -3.0504745921230394],
    [3.14, -0.9820640215804513, 2.6942315912432595, 3.0111412428218496, 0.5553088167162858,
     -2.5567845201297956],
    [2.796345526897559, -1.2515335693355294, 2.757, 2.3154214199856065, -0.7246511716288284,
     -1.7393473779580582],
    [2.8796531640308722, -1.2223464032654832, 2.757, 2.2998266937611413, -0.670886517467789,
     -1.8513202966111917],
    [2.625183216755115, -1.1467275490968658, 2.757, 2.690955457798883, -1.4042835005176997,
     -1.4688704172269538]])
"""Waypoints on the KR60's joint 1 and joint 3 limits (3.14, 2.757 rad) that a blend used to
overshoot by 7e-8 rad."""


@pytest.fixture(scope="module")
def kr60() -> Robot:
    return robot_from_files(ROOT / "robots/generated/KR60.urdf",
                            ROOT / "robots/generated/KR60.srdf")


def _violations(robot: Robot, waypoints: np.ndarray) -> list[str]:
    limits = MotionLimits.from_chain(robot.chain)
    motion = blended(robot.chain.joint_names, waypoints, limits)
    t = np.append(np.arange(0.0, motion.duration, 1e-3), motion.duration)
    q = motion.evaluate(t)[0]
    return finite_difference_violations(t, q, limits.lower, limits.upper, limits.velocity,
                                        limits.acceleration, limits.jerk)


def _polyline(rng: np.random.Generator, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """3-7 waypoints, steps of 0.05-1 rad in random directions, clipped onto the limits (so
    that some waypoints sit exactly on one)."""
    wp = [rng.uniform(lower, upper)]
    for _ in range(int(rng.integers(2, 7))):
        step = rng.normal(size=len(lower)) * rng.uniform(0.05, 1.0)
        wp.append(np.clip(wp[-1] + step, lower, upper))
    return np.array(wp)


def test_a_blend_through_waypoints_on_the_joint_limits_stays_inside_them(kr60: Robot) -> None:
    assert _violations(kr60, ON_A_LIMIT) == []


def test_two_hundred_random_blends_keep_every_limit_at_1_khz(kr60: Robot) -> None:
    """Before the fix, 4 of the first 130 of these broke the jerk limit by up to 6 %."""
    rng = np.random.default_rng(7)
    limits = MotionLimits.from_chain(kr60.chain)
    bad = []
    for k in range(200):
        wp = _polyline(rng, limits.lower, limits.upper)
        found = _violations(kr60, wp)
        if found:
            bad.append(f"polyline {k}: {found}")
    assert bad == []


SLOWER_BLEND = np.array([
    [-1.5457344421712857, 0.5932662516182505, -0.4605334526435172, 2.2917349064715986,
     0.6298249938343425, 2.5899468767566485],
    [-2.101129430160099, 0.61, 0.1880917810972823, 2.9062845158652815, 0.7374817749721083,
     3.036924112284885],
    [-2.4077130836430616, 0.44887338346215694, 0.2632369378173972, 2.524745934157783,
     0.8228011386154351, 3.14],
    [-2.382345461457965, 0.44403829148446883, 0.2577345402255083, 2.5247242793566214,
     0.7955122305046565, 3.1213787642006454],
    [-1.416872067886537, -0.6685284948392353, -0.939885680637621, 2.415459359566622,
     -0.07097370254374535, 3.14]])
"""A path (waypoints on joint limits, a short back-step) whose pass-through timing took 1.09x
as long as resting at every waypoint, before the blend fell back to resting."""


def test_a_blend_is_never_slower_than_resting_at_every_waypoint(kr60: Robot) -> None:
    """Passing through can take longer than stopping (a planner's shelf path at 1.02x, the
    path above at 1.09x): then the rest-to-rest timing is the answer. That path and 300 seeded
    random polylines."""
    from usar_arm.control.timing import stop_at_waypoints

    limits = MotionLimits.from_chain(kr60.chain, 0.5)
    rng = np.random.default_rng(4)
    names = kr60.chain.joint_names
    paths = [SLOWER_BLEND] + [_polyline(rng, kr60.chain.lower(), kr60.chain.upper())
                              for _ in range(300)]
    passed_through = 0
    for path in paths:
        blend, stop = blended(names, path, limits), stop_at_waypoints(names, path, limits)
        assert blend.duration <= stop.duration + 1e-9
        passed_through += blend.fallbacks < len(path) - 2
    assert passed_through > 150  # most paths do pass through their waypoints
