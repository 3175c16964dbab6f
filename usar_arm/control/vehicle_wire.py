"""What a ground vehicle says about itself over the wire, and its poses in REP-103.

``GETCONF {Type Robot}`` gives the maximum wheel spin (``MaxSpeed``, rad/s), ``GETGEO {Type
Robot}`` the wheel radius and separation (m), and for an Ackermann vehicle the steer range
(``MaxFrontSteer``, rad) and the wheel base (m); each sensor type's CONF and GEO give the range
scanner's limits and mount. Nothing is taken from a table: a vehicle is driven with what its
server reports. Poses on the wire are in the USARSim frame (x forward, y right, z down); the
conversion to REP-103 (z up) is :func:`usar_arm.core.spatial.zdown_to_zup_transform`, the one
the arm's discovery uses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from usar_arm.core.errors import ResponseTimeoutError
from usar_arm.core.platform import ACKERMANN_STEERED, SUPPORTED_STEERING
from usar_arm.core.spatial import (
    Array,
    transform_from_xyz_rpy,
    zdown_to_zup_point,
    zdown_to_zup_transform,
)
from usar_arm.core.vehicle_errors import NotAVehicleError, UnsupportedSteeringError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient

SENSOR_TIMEOUT_S = 2.0
"""Seconds to wait for a sensor type's CONF/GEO: UDK says nothing for a type the robot lacks."""


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


def _number(fields: tuple[m.Block, ...], key: str) -> float | None:
    for k, v in fields:
        if k.lower() == key.lower():
            try:
                value = float(v)
            except ValueError:
                return None
            return value if math.isfinite(value) and value > 0 else None
    return None


def _first_sensor(client: UsarClient, type_: str) -> tuple[m.ConfItem, m.GeoItem] | None:
    try:
        conf = client.get_conf(type_, timeout=SENSOR_TIMEOUT_S)
        geo = client.get_geo(type_, timeout=SENSOR_TIMEOUT_S)
    except ResponseTimeoutError:  # (and UnknownComponentError, its subclass)
        return None
    if not isinstance(conf, m.Conf) or not conf.items or not geo.items:
        return None
    return conf.items[0], geo.items[0]


def _scanner(client: UsarClient) -> ScannerInfo | None:
    found = _first_sensor(client, "RangeScanner")
    if found is None:
        return None
    conf, geo = found
    numbers = {k: _number(conf.fields, k) for k in ("MinRange", "MaxRange", "Resolution", "Fov")}
    if any(v is None for v in numbers.values()):
        return None
    mount = pose_zup(geo.location or (0.0, 0.0, 0.0), geo.orientation or (0.0, 0.0, 0.0))
    return ScannerInfo(conf.name, numbers["MinRange"] or 0.0, numbers["MaxRange"] or 0.0,
                       numbers["Resolution"] or 0.0, numbers["Fov"] or 0.0, mount)


def read_vehicle(client: UsarClient, robot: str, timeout: float | None = None) -> VehicleInfo:
    """Ask a spawned vehicle for its CONF and GEO and its sensors' (each wait bounded).

    Raises:
        NotAVehicleError: the robot reports no wheel radius, separation or maximum speed.
        ResponseTimeoutError: the robot's own CONF or GEO did not come within ``timeout``.
    """
    conf = client.get_conf("Robot", timeout=timeout)
    platform_type = conf.type if isinstance(conf, m.PlatformConf) else "robot"
    fields = conf.fields if isinstance(conf, m.PlatformConf) else ()
    try:
        geo = client.get_geo("Robot", timeout=SENSOR_TIMEOUT_S)
        geo_fields = geo.items[0].extra if geo.items else ()
    except ResponseTimeoutError:  # (and UnknownComponentError, its subclass)
        geo_fields = ()
    values = {"MaxSpeed": _number(fields, "MaxSpeed"),
              "WheelRadius": _number(geo_fields, "WheelRadius"),
              "WheelSeparation": _number(geo_fields, "WheelSeparation")}
    steering = next((v for k, v in fields if k.lower() == "steeringtype"), "")
    if steering == ACKERMANN_STEERED:
        front = _number(fields, "MaxFrontSteer")  # (6.28: no front steer, section 10)
        values |= {"WheelBase": _number(geo_fields, "WheelBase"),
                   "MaxFrontSteer": front if front is not None and front < 6.28 else None}
    missing = [k for k, v in values.items() if v is None]
    if missing:
        raise NotAVehicleError(robot, platform_type, missing)
    if steering not in SUPPORTED_STEERING:
        raise UnsupportedSteeringError(
            f"{robot} reports {{SteeringType {steering or '(none given)'}}}: usar-arm drives only "
            f"{' and '.join(SUPPORTED_STEERING)} ground vehicles")
    names = {t: (found[0].name if (found := _first_sensor(client, t)) else None)
             for t in ("GroundTruth", "Odometry", "INS")}
    return VehicleInfo(conf.name if isinstance(conf, m.PlatformConf) else robot, steering,
                       values["WheelRadius"] or 0.0, values["WheelSeparation"] or 0.0,
                       values["MaxSpeed"] or 0.0, names["GroundTruth"], names["Odometry"],
                       names["INS"], _scanner(client), values.get("WheelBase") or 0.0,
                       (values.get("MaxFrontSteer") or 0.0) / 2)


def planar_wire(location: m.Vector3, rpy: m.Vector3) -> tuple[float, float, float]:
    """x, y, yaw in REP-103 of a wire pose (m, rad; z down)."""
    return planar(pose_zup(location, rpy))


def odometry_planar(pose: m.Vector3) -> tuple[float, float, float]:
    """An Odometry reading's (x, y, theta), z down, as x, y, yaw in REP-103."""
    return planar_wire((pose[0], pose[1], 0.0), (0.0, 0.0, pose[2]))


def height_zup(location: m.Vector3) -> float:
    """Height (m, z up) of a wire location."""
    return float(zdown_to_zup_point(location)[2])
