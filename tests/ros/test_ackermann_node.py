"""`usar-arm ros --robot FrontAckerman` in another process, driven by a real rclpy client:
the description steers its front wheels, cmd_vel becomes ``DRIVE {Speed} {FrontSteer}
{RearSteer}`` (forward and a left turn arrive as such in the simulator's ground truth), a turn
on the spot is refused with a log line, a NaN command stops the vehicle."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed: pip install "
                                    "'usar-arm[ros]'")

from tests.ros import helpers as ros
from tests.ros.helpers import Client, NodeProcess


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Client, str, NodeProcess]]:
    with ros.node_session(tmp_path_factory.mktemp("ros-ackermann"),
                          ["--robot", "FrontAckerman", "-v"]) as started:
        yield started


def _truth(client: Client) -> Any:
    return ros.latest_odometry(client)


def test_the_description_steers_the_front_wheels(session: tuple[Client, str, NodeProcess]
                                                 ) -> None:
    _, urdf, _ = session
    assert '"front_left_steer_joint" type="revolute"' in urdf
    assert '"rear_left_steer_joint"' not in urdf


def test_a_nan_command_is_refused_and_the_vehicle_stops(
        session: tuple[Client, str, NodeProcess]) -> None:
    client, _, node = session
    dx, dy = ros.moved_under_nan(client, 0.06)
    assert abs(dx) < 0.003 and abs(dy) < 0.003
    assert "cmd_vel refused, the robot stops" in node.text()


def test_cmd_vel_drives_forward_turning_left_and_a_turn_on_the_spot_is_refused(
        session: tuple[Client, str, NodeProcess]) -> None:
    client, _, node = session
    start = _truth(client)
    ros.publish_twist(client, 0.06, 0.03, 3.0)  # steer atan(0.03 * 0.956 / 0.06) = 0.45 rad, left
    moved = _truth(client)
    heading = ros.odometry_yaw(start)
    dx = moved.pose.pose.position.x - start.pose.pose.position.x
    dy = moved.pose.pose.position.y - start.pose.pose.position.y
    assert dx * math.cos(heading) + dy * math.sin(heading) > 0.1, (dx, dy)
    assert math.remainder(ros.odometry_yaw(moved) - heading, math.tau) > 0.03  # counter-clockwise
    ros.publish_twist(client, 0.0, 0.5, 1.0)  # no forward speed: it stands still
    a = _truth(client)
    ros.publish_twist(client, 0.0, 0.5, 0.5)
    b = _truth(client)
    dx, _, dyaw = ros.pose_change(a, b)
    assert abs(dx) < 0.003 and abs(dyaw) < 0.003
    assert "cmd_vel turns on the spot: an Ackermann vehicle cannot" in node.text()
