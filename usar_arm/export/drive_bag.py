"""A drive of a ground vehicle as a rosbag2 folder (MCAP), for ``ros2 bag play`` and Foxglove.

Frames follow REP-105: ``map`` (the world, REP-103: the world file's x, its y and z negated)
-> ``odom`` (where the odometer started, placed by the first ground truth) -> ``base_footprint``
(the vehicle on the floor) -> ``base_link`` (the chassis origin) -> the scanner. Stamps are the
simulator's time (s) after ``start_ns``.

==================  ==========================  =============================================
topic               type                        content
==================  ==========================  =============================================
``/tf_static``      tf2_msgs/msg/TFMessage      base_footprint -> base_link (the chassis'
                                                height at the start), base_link -> scanner
                                                (its GETGEO mount)
``/tf``             tf2_msgs/msg/TFMessage      map -> odom and odom -> base_footprint, at
                                                every odometry reading
``/odom``           nav_msgs/msg/Odometry       the odometry (odom frame; INS in map when the
                                                vehicle has no odometer)
``/ground_truth``   nav_msgs/msg/Odometry       the GroundTruth sensor (map frame)
``/scan``           sensor_msgs/msg/LaserScan   every scan, ranges as reported
``/cmd_vel``        geometry_msgs/msg/Twist     every velocity command (v, w asked)
==================  ==========================  =============================================
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.control.drive_record import DriveRecord, PoseTrack, odom_origin
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.spatial import Array, rot_z, transform
from usar_arm.export.bag import (
    DISTROS,
    LATCHED_QOS,
    STREAM_QOS,
    BagMessages,
    BagSummary,
    write_topics,
)

_NS = 10**9
TOPICS = {"/tf_static": ("tf2_msgs/msg/TFMessage", LATCHED_QOS),
          "/tf": ("tf2_msgs/msg/TFMessage", STREAM_QOS),
          "/odom": ("nav_msgs/msg/Odometry", STREAM_QOS),
          "/ground_truth": ("nav_msgs/msg/Odometry", STREAM_QOS),
          "/scan": ("sensor_msgs/msg/LaserScan", STREAM_QOS),
          "/cmd_vel": ("geometry_msgs/msg/Twist", STREAM_QOS)}
"""Topic -> (type, QoS), in connection order."""


def _planar(pose: Array | tuple[float, float, float]) -> Array:
    """A planar pose (x, y, yaw) as a 4x4 transform."""
    return transform(rot_z(float(pose[2])), (float(pose[0]), float(pose[1]), 0.0))


class _DriveMessages:
    """The drive's messages, stamped in ns after the first ground truth."""

    def __init__(self, build: BagMessages, record: DriveRecord):
        self.build = build
        self.types = build.types
        self.record = record
        self.t0 = float(record.truth.t[0])

    def offset(self, t: float) -> int:
        return max(0, round((t - self.t0) * _NS))

    def odometry(self, track: PoseTrack, frame: str) -> list[tuple[int, Any]]:
        """nav_msgs/Odometry per sample; the twist from the finite difference (base frame)."""
        ty = self.types
        out = []
        for k, (t, pose) in enumerate(zip(track.t, track.pose, strict=True)):
            v = w = 0.0
            if k > 0 and track.t[k] > track.t[k - 1]:
                dt = float(track.t[k] - track.t[k - 1])
                step = pose[:2] - track.pose[k - 1, :2]
                v = float(math.cos(pose[2]) * step[0] + math.sin(pose[2]) * step[1]) / dt
                w = math.remainder(float(pose[2] - track.pose[k - 1, 2]), 2 * math.pi) / dt
            qz, qw = math.sin(pose[2] / 2), math.cos(pose[2] / 2)
            p = ty["geometry_msgs/msg/Pose"](ty["geometry_msgs/msg/Point"](
                float(pose[0]), float(pose[1]), 0.0), ty["geometry_msgs/msg/Quaternion"](
                0.0, 0.0, float(qz), float(qw)))
            twist = ty["geometry_msgs/msg/Twist"](ty["geometry_msgs/msg/Vector3"](v, 0.0, 0.0),
                                                  ty["geometry_msgs/msg/Vector3"](0.0, 0.0, w))
            out.append((self.offset(t), ty["nav_msgs/msg/Odometry"](
                self.build.header(self.offset(t), frame), "base_footprint",
                ty["geometry_msgs/msg/PoseWithCovariance"](p, np.zeros(36)),
                ty["geometry_msgs/msg/TwistWithCovariance"](twist, np.zeros(36)))))
        return out

    def scans(self) -> list[tuple[int, Any]]:
        """sensor_msgs/LaserScan per scan: right (-fov/2) to left (+fov/2), REP-103."""
        scanner = self.record.vehicle.scanner
        if scanner is None:
            return []
        out, times = [], [s.t for s in self.record.scans]
        period = float(np.median(np.diff(times))) if len(times) > 1 else 0.0
        for scan in self.record.scans:
            n = len(scan.ranges)
            step = scan.fov / (n - 1) if n > 1 else 0.0
            out.append((self.offset(scan.t), self.types["sensor_msgs/msg/LaserScan"](
                self.build.header(self.offset(scan.t), scanner.name), -scan.fov / 2,
                scan.fov / 2, step, 0.0, period, scanner.min_range, scanner.max_range,
                np.asarray(scan.ranges, dtype=np.float32), np.zeros(0, dtype=np.float32))))
        return out

    def tf(self, track: PoseTrack, origin: tuple[float, float, float]) -> list[tuple[int, Any]]:
        """map -> odom (constant) and odom -> base_footprint per odometry sample."""
        b, msg = self.build, self.types["tf2_msgs/msg/TFMessage"]
        map_odom = _planar(origin)
        return [(self.offset(t), msg([b.transform(self.offset(t), "map", "odom", map_odom),
                                      b.transform(self.offset(t), "odom", "base_footprint",
                                                  _planar(pose))]))
                for t, pose in zip(track.t, track.pose, strict=True)]

    def tf_static(self) -> Any:
        b, scanner = self.build, self.record.vehicle.scanner
        transforms = [b.transform(0, "base_footprint", "base_link",
                                  transform(None, (0.0, 0.0, self.record.height_m)))]
        if scanner is not None:
            transforms.append(b.transform(0, "base_link", scanner.name, scanner.mount))
        return self.types["tf2_msgs/msg/TFMessage"](transforms)

    def cmd_vel(self) -> list[tuple[int, Any]]:
        vec, twist = self.types["geometry_msgs/msg/Vector3"], self.types["geometry_msgs/msg/Twist"]
        return [(self.offset(c.t), twist(vec(c.v, 0.0, 0.0), vec(0.0, 0.0, c.w)))
                for c in self.record.commands]


def write_drive_bag(path: str | Path, record: DriveRecord, *,
                    start_ns: int = 1_700_000_000 * _NS, overwrite: bool = False,
                    distro: str = "humble") -> BagSummary:
    """Write a drive as a rosbag2 folder (MCAP) at ``path``, atomically.

    Raises:
        InvalidInputError: no ground truth was recorded, an unknown distro, or ``path`` exists
            (and ``overwrite`` is False, or it is no bag folder).
    """
    if distro not in DISTROS:
        raise InvalidInputError(f"unknown ROS 2 distro '{distro}'; expected one of "
                                f"{', '.join(DISTROS)}")
    if len(record.truth) == 0:
        raise InvalidInputError("the drive recorded no ground truth: nothing to write")
    build = BagMessages(distro, int(start_ns))
    msgs = _DriveMessages(build, record)
    has_odometer = len(record.odometry) > 0
    odom = record.odometry if has_odometer else record.ins
    origin = (odom_origin(record.truth.pose[0], record.odometry.pose[0]) if has_odometer
              else (0.0, 0.0, 0.0))
    messages = {"/tf_static": [(0, msgs.tf_static())], "/tf": msgs.tf(odom, origin),
                "/odom": msgs.odometry(odom, "odom" if has_odometer else "map"),
                "/ground_truth": msgs.odometry(record.truth, "map"), "/scan": msgs.scans(),
                "/cmd_vel": msgs.cmd_vel()}
    return write_topics(Path(path), TOPICS, messages, build, overwrite=overwrite, distro=distro)
