"""DRIVE moves the P3AT as UDK interprets it, and its odometry and INS follow the ground truth.

Speeds are measured from the GroundTruth stream over real TCP: a wheel spinning at w rad/s
carries the P3AT (WheelRadius 0.098 m) at 0.098 w m/s when it rolls without slipping.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest

from tests.sim.p3at_client import LineClient, spawn_p3at
from usar_arm.usarsim import messages as m

RADIUS = 0.098
MAX_SPIN = 1.3
"""P3AT.uc WheelJoint MaxVelocity (rad/s)."""


@pytest.fixture
def p3at(rooms_port: int) -> Iterator[LineClient]:
    client = spawn_p3at(rooms_port, "RobotStart1", settle_s=0.5)
    yield client
    client.close()


def _truth(client: LineClient) -> m.Sen:
    msg = client.latest(m.Sen, "GndTruth")
    assert isinstance(msg, m.Sen) and msg.location is not None and msg.orientation is not None
    assert msg.time is not None
    return msg


def _speed(client: LineClient, drive: str, seconds: float = 1.5) -> tuple[float, float]:
    """Forward speed (m/s, along the heading) and yaw rate (rad/s) under ``drive``, measured
    after a 0.5 s run-up."""
    client.send(drive)
    client.pump(0.5)
    a = _truth(client)
    client.pump(seconds)
    b = _truth(client)
    assert a.location and b.location and a.orientation and b.orientation and a.time and b.time
    dt = b.time - a.time
    yaw = a.orientation[2]
    dx, dy = b.location[0] - a.location[0], b.location[1] - a.location[1]
    forward = (dx * math.cos(yaw) + dy * math.sin(yaw)) / dt
    dyaw = math.remainder(b.orientation[2] - a.orientation[2], 2 * math.pi)
    return forward, dyaw / dt


def test_drive_speeds_are_wheel_spins_in_rad_s_clamped_to_max_velocity(p3at: LineClient) -> None:
    v, w = _speed(p3at, "DRIVE {Left 1.0} {Right 1.0}")
    assert v == pytest.approx(1.0 * RADIUS, rel=0.05) and abs(w) < 0.02
    v, w = _speed(p3at, "DRIVE {Left -0.8} {Right -0.8}")
    assert v == pytest.approx(-0.8 * RADIUS, rel=0.05)
    v, _ = _speed(p3at, "DRIVE {Left 50} {Right 50}")  # clamped to MaxVelocity
    assert v == pytest.approx(MAX_SPIN * RADIUS, rel=0.05)


def test_normalized_drive_is_a_percentage_of_max_velocity_and_sticks(p3at: LineClient) -> None:
    v, _ = _speed(p3at, "DRIVE {Left 50} {Right 50} {Normalized true}")
    assert v == pytest.approx(0.5 * MAX_SPIN * RADIUS, rel=0.05)
    v, _ = _speed(p3at, "DRIVE {Left -100} {Right -100}")  # still normalized, as in UDK
    assert v == pytest.approx(-MAX_SPIN * RADIUS, rel=0.05)
    v, _ = _speed(p3at, "DRIVE {Left 250} {Right 250}")  # beyond 100 %: clamped
    assert v == pytest.approx(MAX_SPIN * RADIUS, rel=0.05)
    v, _ = _speed(p3at, "DRIVE {Left 1} {Right 1} {Normalized false}")
    assert v == pytest.approx(RADIUS, rel=0.05)


def test_left_faster_than_right_turns_right_and_stop_stops(p3at: LineClient) -> None:
    """In the z-down frame a right turn is a growing yaw."""
    _, w = _speed(p3at, "DRIVE {Left 1.3} {Right -1.3}")
    assert w > 0.05
    _, w = _speed(p3at, "DRIVE {Left -1.3} {Right 1.3}")
    assert w < -0.05
    v, w = _speed(p3at, "DRIVE {Left 0} {Right 0}")
    assert abs(v) < 0.005 and abs(w) < 0.01


def test_odometry_and_ins_follow_the_ground_truth_driving_straight(p3at: LineClient) -> None:
    start = _truth(p3at)
    odo0 = p3at.latest(m.Odometry)
    p3at.send("DRIVE {Left 1.3} {Right 1.3}")
    p3at.pump(4.0)
    p3at.send("DRIVE {Left 0} {Right 0}")
    p3at.pump(0.6)
    end = _truth(p3at)
    odo = p3at.latest(m.Odometry)
    ins = p3at.latest(m.Ins)
    assert isinstance(odo0, m.Odometry) and isinstance(odo, m.Odometry) and isinstance(ins, m.Ins)
    assert start.location and end.location
    travelled = math.dist(start.location[:2], end.location[:2])
    assert travelled > 0.45
    odo_travelled = math.dist(odo0.pose[:2], odo.pose[:2])
    # Rolling without slip on a straight line: within 3 % (plus the 4-decimal print).
    assert odo_travelled == pytest.approx(travelled, rel=0.03, abs=0.002)
    assert abs(odo.pose[2] - odo0.pose[2]) < 0.02
    # The INS (Sigma 0 in DefaultUSAR.ini: no noise) is the mount's start plus the chassis'
    # motion, printed with 2 decimals.
    assert ins.location[0] == pytest.approx(end.location[0], abs=0.011)
    assert ins.location[1] == pytest.approx(end.location[1], abs=0.011)
    assert ins.location[2] == pytest.approx(end.location[2] - 0.2, abs=0.011)
