"""What a drive recorded, and how far the vehicle's own estimates drifted from the truth.

Every pose is planar, REP-103 (x, y in m, yaw in rad counter-clockwise), stamped with the
simulator's time (s). Ground truth and INS are in the world ("map") frame; odometry is in its
own frame, the pose the vehicle had when the odometer started (``odom``): :func:`odom_in_map`
anchors it at the first ground truth the drive saw.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from usar_arm.control.vehicle_wire import VehicleInfo
from usar_arm.core.spatial import Array


@dataclass(frozen=True)
class PoseTrack:
    """Stamped planar poses: t (n,) s and pose (n, 3) x, y (m), yaw (rad)."""

    t: Array
    pose: Array

    @staticmethod
    def of(samples: list[tuple[float, float, float, float]]) -> PoseTrack:
        """From (t, x, y, yaw) tuples."""
        data = np.asarray(samples, dtype=float).reshape(-1, 4)
        return PoseTrack(data[:, 0], data[:, 1:])

    def __len__(self) -> int:
        return len(self.t)

    def length_m(self) -> float:
        """Length (m) of the path the positions trace."""
        return float(np.sum(np.linalg.norm(np.diff(self.pose[:, :2], axis=0), axis=1)))


@dataclass(frozen=True)
class Scan:
    """One laser scan: stamp (s) and ranges (m) from the scanner's right to its left."""

    t: float
    ranges: tuple[float, ...]
    fov: float


@dataclass(frozen=True)
class Command:
    """A velocity command sent at ``t`` (s): asked v (m/s) and w (rad/s), the wheel spins
    sent (rad/s) and whether they were scaled down to the vehicle's limit."""

    t: float
    v: float
    w: float
    left: float
    right: float
    clamped: bool
    steer: float = 0.0
    """The front steer sent (rad, REP-103: positive left); 0 on a skid-steered vehicle, whose
    ``left`` and ``right`` are its sides' spins (an Ackermann vehicle's both its one spin)."""


@dataclass(frozen=True)
class DriveRecord:
    """A drive: the vehicle, its streams, its commands and how it ended.

    Attributes:
        height_m: the chassis origin's height above the floor at the start (m).
        reached: every waypoint reached (or the script played to its end).
        interrupted: stopped by Ctrl-C (the vehicle was stopped; the record is kept).
    """

    vehicle: VehicleInfo
    truth: PoseTrack
    odometry: PoseTrack
    ins: PoseTrack
    scans: tuple[Scan, ...]
    commands: tuple[Command, ...]
    height_m: float
    reached: bool
    interrupted: bool = False
    goals: tuple[tuple[float, float], ...] = field(default_factory=tuple)


def compose(a: tuple[float, float, float], b: Array) -> Array:
    """Planar poses ``b`` (n, 3) expressed in the frame of pose ``a``, as poses in a's parent."""
    c, s = math.cos(a[2]), math.sin(a[2])
    out = np.empty_like(b)
    out[:, 0] = a[0] + c * b[:, 0] - s * b[:, 1]
    out[:, 1] = a[1] + s * b[:, 0] + c * b[:, 1]
    out[:, 2] = a[2] + b[:, 2]
    return out


def odom_origin(truth: Sequence[float], odometry: Sequence[float]) -> tuple[float, float, float]:
    """The odom frame in the map (x, y, yaw): where a ground truth pose and the odometry pose
    of the same moment (x, y, yaw each) agree."""
    yaw = float(truth[2] - odometry[2])
    c, s = math.cos(yaw), math.sin(yaw)
    return (float(truth[0] - c * odometry[0] + s * odometry[1]),
            float(truth[1] - s * odometry[0] - c * odometry[1]), yaw)


def odom_in_map(record: DriveRecord) -> PoseTrack:
    """The odometry track in the map frame (anchored by :func:`odom_origin`)."""
    if not len(record.odometry) or not len(record.truth):
        return record.odometry
    origin = odom_origin(record.truth.pose[0], record.odometry.pose[0])
    return PoseTrack(record.odometry.t, compose(origin, record.odometry.pose))


@dataclass(frozen=True)
class Drift:
    """An estimate against the ground truth at the end of a drive.

    Attributes:
        source: ``odometry`` or ``ins``. position_m: final position error (m).
        heading_rad: final heading error (rad, wrapped to [-pi, pi]).
        percent_of_distance: position_m over the true distance driven (%).
        distance_m: the true distance driven (m).
    """

    source: str
    position_m: float
    heading_rad: float
    percent_of_distance: float
    distance_m: float


def drift(source: str, estimate: PoseTrack, truth: PoseTrack) -> Drift | None:
    """The final error of ``estimate`` (map frame) against the truth at the same time (the
    truth interpolated at the estimate's last stamp); None without samples."""
    if len(estimate) == 0 or len(truth) < 2:
        return None
    t = float(min(estimate.t[-1], truth.t[-1]))
    k = int(np.searchsorted(estimate.t, t, side="right")) - 1
    est = estimate.pose[max(k, 0)]
    x, y = (float(np.interp(t, truth.t, truth.pose[:, i])) for i in (0, 1))
    yaw = float(np.interp(t, truth.t, np.unwrap(truth.pose[:, 2])))
    position = math.hypot(est[0] - x, est[1] - y)
    heading = math.remainder(float(est[2]) - yaw, 2 * math.pi)
    distance = truth.length_m()
    percent = 100 * position / distance if distance > 0 else math.nan
    return Drift(source, position, heading, percent, distance)


def laser_hits(record: DriveRecord, every: int = 1) -> Array:
    """Where the scanner's rays ended (m, map frame, (k, 2)), each scan placed by the ground
    truth at its stamp (interpolated) and the scanner's mount; rays at the maximum range (no
    hit) are left out. ``every``: use every n-th scan."""
    scanner, truth = record.vehicle.scanner, record.truth
    if scanner is None or len(truth) < 2 or not record.scans:
        return np.zeros((0, 2))
    yaw_track = np.unwrap(truth.pose[:, 2])
    out = []
    for scan in record.scans[::every]:
        n = len(scan.ranges)
        ranges = np.asarray(scan.ranges, dtype=float)
        angles = -scan.fov / 2 + np.arange(n) * (scan.fov / (n - 1) if n > 1 else 0.0)
        keep = (ranges < scanner.max_range) & (ranges >= scanner.min_range)
        local = np.stack([ranges * np.cos(angles), ranges * np.sin(angles),
                          np.zeros(n), np.ones(n)])[:, keep]
        x, y = (float(np.interp(scan.t, truth.t, truth.pose[:, i])) for i in (0, 1))
        yaw = float(np.interp(scan.t, truth.t, yaw_track))
        c, s = math.cos(yaw), math.sin(yaw)
        base = np.array([[c, -s, 0, x], [s, c, 0, y], [0, 0, 1, 0], [0, 0, 0, 1.0]])
        out.append((base @ scanner.mount @ local)[:2].T)
    return np.concatenate(out) if out else np.zeros((0, 2))
