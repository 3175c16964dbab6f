"""The platform's state streams as plain data: odometry from a sensor's SEN lines, the ground
truth, and a scan's LaserScan fields (no ROS types; REP-103, m, rad, s).

* INS (``SEN {Type INS} {Location} {Orientation}``): the sensor's pose in USARSim's z-down
  world; base_footprint follows from the sensor's mount and base_link's height. The odom frame
  is where base_footprint stood at the first reading (its position and heading: odom is level).
* Odometry (``{Pose x,y,theta}``, z-down, from zero at spawn): base_footprint in odom directly.
* GroundTruth: the chassis pose in the z-down world, published as its own tree (``truth/``).

Twists are finite differences of successive poses, in the child frame (base_footprint).
A scan's rays run right to left (UDK), i.e. counter-clockwise from ``-fov/2`` in REP-103.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usar_arm.core.platform import Scanner
from usar_arm.core.spatial import (
    Array,
    invert,
    matrix_to_rpy,
    rot_z,
    transform,
    transform_from_xyz_rpy,
    zdown_to_zup_transform,
)
from usar_arm.usarsim import messages as m


@dataclass(frozen=True)
class PoseSample:
    """A pose of base_footprint (4x4, m) at ``time`` (s) with its twist in the child frame:
    ``linear`` (m/s) and ``angular`` (rad/s)."""

    time: float
    pose: Array
    linear: tuple[float, float, float] = (0.0, 0.0, 0.0)
    angular: tuple[float, float, float] = (0.0, 0.0, 0.0)


def world_pose(location: m.Vector3, orientation: m.Vector3) -> Array:
    """A z-down wire pose (m, roll-pitch-yaw rad) as a 4x4 pose in the REP-103 world."""
    return zdown_to_zup_transform(transform_from_xyz_rpy(location, orientation))


def level(pose: Array) -> Array:
    """The pose's position and heading only (a level frame)."""
    yaw = math.atan2(pose[1, 0], pose[0, 0])
    return transform(rot_z(yaw), pose[:3, 3])


class PoseTracker:
    """Turns one sensor's readings into base_footprint samples.

    Args:
        sensor_to_footprint: base_footprint in the sensor's frame (4x4, m): the inverse of the
            sensor's mount, times base_link -> base_footprint.
        relative: re-origin at the first reading (odom) or keep the world (ground truth).
    """

    def __init__(self, sensor_to_footprint: Array, relative: bool = True):
        self.offset = np.asarray(sensor_to_footprint, float)
        self.relative = relative
        self.origin: Array | None = None
        self.last: PoseSample | None = None

    def update(self, time_s: float, sensor_pose: Array) -> PoseSample:
        """The sample for the sensor's pose ``sensor_pose`` (4x4, REP-103) at ``time_s``."""
        pose = np.asarray(sensor_pose, float) @ self.offset
        if self.relative:
            if self.origin is None:
                self.origin = invert(level(pose))
            pose = self.origin @ pose
        linear, angular = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        last = self.last
        if last is not None and time_s > last.time:
            dt = time_s - last.time
            rot = pose[:3, :3]
            v = rot.T @ (pose[:3, 3] - last.pose[:3, 3]) / dt
            delta = last.pose[:3, :3].T @ rot
            rates = np.array(matrix_to_rpy(delta)) / dt
            linear = (float(v[0]), float(v[1]), float(v[2]))
            angular = (float(rates[0]), float(rates[1]), float(rates[2]))
        self.last = PoseSample(time_s, pose, linear, angular)
        return self.last


def sensor_pose(msg: m.Message) -> Array | None:
    """The REP-103 pose a pose sensor's line reports (its own frame), or None for other lines.

    Odometry's ``{Pose x,y,theta}`` is already relative to the spawn: its pose is on the ground
    (z = 0) with heading -theta (z-down yaw turns right)."""
    if isinstance(msg, m.Odometry):
        x, y, theta = msg.pose
        return transform(rot_z(-theta), (x, -y, 0.0))
    if isinstance(msg, (m.Ins, m.Sen)) and msg.location is not None \
            and msg.orientation is not None:
        return world_pose(msg.location, msg.orientation)
    return None


@dataclass(frozen=True)
class ScanFields:
    """The fields of a sensor_msgs/LaserScan (rad, m, s)."""

    angle_min: float
    angle_max: float
    angle_increment: float
    range_min: float
    range_max: float
    scan_time: float
    ranges: tuple[float, ...]


def scan_fields(scan: m.RangeScan, scanner: Scanner, period: float) -> ScanFields:
    """A scan as LaserScan fields: the angles from the line's own FOV and Resolution, the ranges
    as reported, range limits from the scanner's CONF, ``scan_time`` from its ScanInterval (else
    ``period``, the time between its last two scans, s)."""
    increment = scan.resolution
    angle_min = -scan.fov / 2.0
    angle_max = angle_min + increment * max(len(scan.ranges) - 1, 0)
    interval = scanner.scan_interval if scanner.scan_interval else period
    return ScanFields(angle_min, angle_max, increment, scanner.min_range, scanner.max_range,
                      interval, scan.ranges)
