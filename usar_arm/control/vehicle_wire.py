"""What the drive needs of a ground vehicle, and its poses in REP-103.

The vehicle is learnt once, by :func:`usar_arm.discover.platform.learn_platform` (its CONF and
GEO, each sensor's): :func:`vehicle_info` keeps what driving needs, the maximum wheel spin
(rad/s), the wheel radius and separation (m), for an Ackermann vehicle the steer limit (rad) and
wheel base (m), the localisation sensors' names and the range scanner. Nothing is taken from a
table: a vehicle is driven with what its server reports. Poses on the wire are in the USARSim
frame (x forward, y right, z down); the conversion to REP-103 (z up) is
:func:`usar_arm.core.spatial.zdown_to_zup_transform`, the one the arm's discovery uses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from usar_arm.core.platform import ACKERMANN_STEERED, PlatformDescription
from usar_arm.core.spatial import (
    Array,
    transform_from_xyz_rpy,
    zdown_to_zup_point,
    zdown_to_zup_transform,
)
from usar_arm.usarsim import messages as m


@dataclass(frozen=True)
class ScannerInfo:
    """A range scanner: name, ranges (m), angular step and field of view (rad, as reported),
    and its mount on the chassis in REP-103 (4x4, base_link -> scanner)."""

    name: str
    min_range: float
    max_range: float
    resolution: float
    fov: float
    mount: Array


@dataclass(frozen=True)
class VehicleInfo:
    """A ground vehicle as its server describes it.

    Attributes:
        name: the platform's name (its class, e.g. ``P3AT``). steering: e.g. ``SkidSteered``.
        wheel_radius, wheel_separation: m. max_wheel_speed: rad/s per wheel.
        truth, odometry, ins: the names of its GroundTruth, Odometry and INS sensors (None when
            it has none). scanner: its first range scanner (None when it has none).
        wheel_base: front to rear axle (m). max_steer: the largest front steer either way
            (rad; half the CONF's MaxFrontSteer range). Both 0 on a skid-steered vehicle.
    """

    name: str
    steering: str
    wheel_radius: float
    wheel_separation: float
    max_wheel_speed: float
    truth: str | None
    odometry: str | None
    ins: str | None
    scanner: ScannerInfo | None
    wheel_base: float = 0.0
    max_steer: float = 0.0

    @property
    def ackermann(self) -> bool:
        """Whether it is driven by a wheel spin and a steer (docs/protocol.md section 10)."""
        return self.steering == ACKERMANN_STEERED

    @property
    def max_speed(self) -> float:
        """Top forward speed (m/s): both wheels at their maximum spin."""
        return self.max_wheel_speed * self.wheel_radius


def pose_zup(location: m.Vector3, rpy: m.Vector3) -> Array:
    """A wire pose (m, rad; z down) as a REP-103 transform (4x4)."""
    return zdown_to_zup_transform(transform_from_xyz_rpy(location, rpy))


def planar(pose: Array) -> tuple[float, float, float]:
    """x, y (m) and yaw (rad, counter-clockwise from x) of a REP-103 transform."""
    return float(pose[0, 3]), float(pose[1, 3]), math.atan2(float(pose[1, 0]),
                                                            float(pose[0, 0]))


def vehicle_info(desc: PlatformDescription) -> VehicleInfo:
    """What the drive needs of a learnt vehicle (:func:`usar_arm.discover.platform.
    learn_platform`, the one reading of a vehicle's CONF and GEO): its wheels, its localisation
    sensors' names (hidden ones included: their readings stream though their mount is unknown)
    and its first range scanner."""
    named = [(s.type, s.name) for s in desc.sensors]
    named += [tuple(h.split(" ", 1)) for h in desc.hidden]  # type: ignore[misc]

    def first(type_: str) -> str | None:
        return next((name for t, name in named if t.lower() == type_.lower()), None)

    scanners = [s for s in desc.sensors_of("RangeScanner") if s.scanner is not None]
    scanner = None
    if scanners:
        s = scanners[0]
        assert s.scanner is not None
        scanner = ScannerInfo(s.name, s.scanner.min_range, s.scanner.max_range,
                              s.scanner.resolution, s.scanner.fov,
                              transform_from_xyz_rpy(s.xyz, s.rpy))
    return VehicleInfo(desc.name, desc.steering_type, desc.wheel_radius, desc.wheel_separation,
                       desc.max_speed, first("GroundTruth"), first("Odometry"), first("INS"),
                       scanner, desc.wheel_base if desc.ackermann else 0.0,
                       desc.max_front_steer)


def planar_wire(location: m.Vector3, rpy: m.Vector3) -> tuple[float, float, float]:
    """x, y, yaw in REP-103 of a wire pose (m, rad; z down)."""
    return planar(pose_zup(location, rpy))


def odometry_planar(pose: m.Vector3) -> tuple[float, float, float]:
    """An Odometry reading's (x, y, theta), z down, as x, y, yaw in REP-103."""
    return planar_wire((pose[0], pose[1], 0.0), (0.0, 0.0, pose[2]))


def height_zup(location: m.Vector3) -> float:
    """Height (m, z up) of a wire location."""
    return float(zdown_to_zup_point(location)[2])
