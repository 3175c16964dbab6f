"""The platform's state as plain data: wire poses to REP-103, odometry re-origined at the first
reading with twists in the child frame, a scan's LaserScan fields (docs/ros.md section 8)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usar_arm.core.platform import Scanner
from usar_arm.core.spatial import transform
from usar_arm.ros.platform_state import PoseTracker, scan_fields, sensor_pose
from usar_arm.usarsim import messages as m


def _yaw(pose: np.ndarray) -> float:
    return math.atan2(pose[1, 0], pose[0, 0])


def test_a_z_down_pose_turned_right_is_a_negative_yaw_in_rep103() -> None:
    pose = sensor_pose(m.Ins("InsTest", (1.0, 2.0, -0.3), (0.0, 0.0, 0.5)))
    assert pose is not None
    assert pose[:3, 3] == pytest.approx([1.0, -2.0, 0.3])  # y right -> left, z down -> up
    assert _yaw(pose) == pytest.approx(-0.5)
    odo = sensor_pose(m.Odometry("Odometer", (0.5, 0.25, 0.1)))
    assert odo is not None and odo[:3, 3] == pytest.approx([0.5, -0.25, 0.0])
    assert _yaw(odo) == pytest.approx(-0.1)
    assert sensor_pose(m.Sen("Sonar", "S1")) is None


def test_odom_starts_at_identity_and_its_twist_is_in_the_child_frame() -> None:
    mount_up = transform(pos=(0.0, 0.0, 0.2))  # the sensor 0.2 m above base_footprint
    tracker = PoseTracker(np.linalg.inv(mount_up), relative=True)
    heading = 1.0
    start = transform(np.array([[math.cos(heading), -math.sin(heading), 0],
                                [math.sin(heading), math.cos(heading), 0], [0, 0, 1]]),
                      (3.0, 4.0, 0.2))
    first = tracker.update(10.0, start)
    assert first.pose == pytest.approx(np.eye(4))
    ahead = start.copy()
    ahead[:3, 3] += 0.05 * np.array([math.cos(heading), math.sin(heading), 0.0])  # 0.05 m
    second = tracker.update(10.5, ahead)
    assert second.pose[:3, 3] == pytest.approx([0.05, 0.0, 0.0])
    assert second.linear == pytest.approx((0.1, 0.0, 0.0))  # m/s, forward in base_footprint
    assert second.angular == pytest.approx((0.0, 0.0, 0.0))


def test_ground_truth_keeps_the_world() -> None:
    tracker = PoseTracker(np.eye(4), relative=False)
    pose = transform(pos=(3.0, 4.0, 0.0))
    assert tracker.update(0.0, pose).pose == pytest.approx(pose)


def test_scan_fields_follow_the_line_and_the_conf() -> None:
    scan = m.RangeScan("lms200", 0.0174, 3.1414, tuple([5.0] * 181), 1.0)
    fields = scan_fields(scan, Scanner(20.0, 0.1, 0.0174, 3.1414, None), period=0.2)
    assert fields.angle_min == pytest.approx(-1.5707)
    assert fields.angle_max == pytest.approx(-1.5707 + 180 * 0.0174)
    assert (fields.range_min, fields.range_max, fields.scan_time) == (0.1, 20.0, 0.2)
    assert len(fields.ranges) == 181
    with_interval = scan_fields(scan, Scanner(20.0, 0.1, 0.0174, 3.1414, 0.25), period=0.2)
    assert with_interval.scan_time == 0.25
