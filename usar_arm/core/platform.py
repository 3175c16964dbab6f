"""The data model of a wheeled mobile platform (a ground vehicle such as the P3AT), as learnt.

Everything is in REP-103 (x forward, y left, z up), SI units (m, rad, s, kg), relative to the
platform's ``base_link`` (the chassis origin USARSim reports the robot's pose at). No I/O here:
:mod:`usar_arm.discover.platform` builds a :class:`PlatformDescription` from the wire, and
:mod:`usar_arm.urdf.platform` writes its URDF.

Frame names follow REP-105 by default (``base_footprint`` on the ground under ``base_link``,
sensor frames ``<sensor>_link`` in lower case); :data:`SEED_FRAMES` gives the 2012
``usar_urdf`` names (``base_link`` the root, sensors by their USARSim names).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from usar_arm.core.spatial import Array, transform_from_xyz_rpy

Vec3 = tuple[float, float, float]

SKID_STEERED = "SkidSteered"
"""UDK's SkidSteeredVehicle: two sides of wheels at two speeds (DRIVE {Left} {Right})."""
ACKERMANN_STEERED = "AckermanSteered"
"""UDK's AckermanSteeredVehicle (spelt with one n): one wheel spin and steer angles (DRIVE
{Speed} {FrontSteer} {RearSteer}, docs/protocol.md section 10)."""
SUPPORTED_STEERING = (SKID_STEERED, ACKERMANN_STEERED)
"""The steering types usar-arm can describe and drive."""
WHEEL_WIDTH_M = 0.05
"""The wheels' width (m) drawn in the URDF: the wire does not give it (labelled as assumed)."""


@dataclass(frozen=True)
class Wheel:
    """One wheel: its side, its end (front/rear) and its centre in base_link (m)."""

    side: str
    end: str
    xyz: Vec3

    @property
    def name(self) -> str:
        """``front_left`` etc.: the wheel's link is ``<name>_wheel``."""
        return f"{self.end}_{self.side}"


@dataclass(frozen=True)
class Scanner:
    """A range scanner's settings as its CONF gives them.

    Attributes:
        max_range, min_range: m. resolution: angle between two rays (rad). fov: the field of
        view (rad). scan_interval: s between two scans (None: the CONF does not say; UDK's
        RangeScanner CONF has no ScanInterval).
    """

    max_range: float
    min_range: float
    resolution: float
    fov: float
    scan_interval: float | None = None


@dataclass(frozen=True)
class SensorFrame:
    """A sensor mounted on the chassis.

    Attributes:
        type: its USARSim type (``RangeScanner``, ``INS``...). name: its USARSim name.
        xyz: its mount position in base_link (m). rpy: its mount orientation (rad, URDF's
        fixed-axis roll, pitch, yaw). scan_interval: s between readings (None if not sent).
        scanner: the scanner's settings (range scanners only).
    """

    type: str
    name: str
    xyz: Vec3
    rpy: Vec3
    scan_interval: float | None = None
    scanner: Scanner | None = None


@dataclass(frozen=True)
class PlatformDescription:
    """A ground vehicle as learnt over the wire (REP-103, SI).

    Attributes:
        name: the robot's name (its CONF Name). robot_class: e.g. ``USARBot.P3AT``.
        platform_type: the CONF Type (``GroundVehicle``). steering_type: ``SkidSteered`` or
        ``AckermanSteered``.
        mass: kg. max_speed: the wheels' highest spin speed (rad/s). max_torque: the drive's
        torque limit (N m).
        wheel_radius, wheel_separation (left to right), wheel_base (front to rear): m.
        dimensions: the GEO Dimensions (m). axle_height: the wheel axles' height below
        base_link (m; the wire does not give it: assumed 0, see ``notes``).
        wheels: the four wheels. sensors: the sensors placed by their GEO.
        hidden: ``Type Name`` of sensors whose GETGEO gave nothing (no frame written).
        unknown: ``Type Name`` of sensors of a type usar-arm does not know (not asked about).
        notes: what was assumed, for the files' comments.
        max_front_steer, max_rear_steer: the largest steer angle either way (rad): half the
        range CONF MaxFrontSteer/MaxRearSteer reports; 0 for a wheel set that does not steer
        (a skid-steered vehicle, or the 6.28 UDK prints when no joint steers).
    """

    name: str
    robot_class: str
    platform_type: str
    steering_type: str
    mass: float
    max_speed: float
    max_torque: float
    wheel_radius: float
    wheel_separation: float
    wheel_base: float
    dimensions: Vec3
    axle_height: float
    wheels: tuple[Wheel, ...]
    sensors: tuple[SensorFrame, ...]
    hidden: tuple[str, ...] = ()
    unknown: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    max_front_steer: float = 0.0
    max_rear_steer: float = 0.0

    @property
    def ackermann(self) -> bool:
        """Whether the vehicle steers its wheels (DRIVE {Speed} {FrontSteer} {RearSteer})."""
        return self.steering_type == ACKERMANN_STEERED

    def sensor(self, name: str) -> SensorFrame:
        """The sensor called ``name`` (any case); KeyError naming the sensors otherwise."""
        for s in self.sensors:
            if s.name.lower() == name.lower():
                return s
        raise KeyError(f"no sensor '{name}'; the platform has: "
                       f"{', '.join(s.name for s in self.sensors) or 'none'}")

    def sensors_of(self, type_: str) -> tuple[SensorFrame, ...]:
        """The sensors of a USARSim type (any case)."""
        return tuple(s for s in self.sensors if s.type.lower() == type_.lower())

    @property
    def footprint_height(self) -> float:
        """base_link's height above the ground under it (m): axle height + wheel radius."""
        return self.axle_height + self.wheel_radius

    @property
    def body_size(self) -> Vec3:
        """The body box drawn in the URDF (m): wheel base plus a wheel's diameter long, the
        gap between the wheels wide, a wheel radius high."""
        return (self.wheel_base + 2 * self.wheel_radius,
                max(self.wheel_separation - WHEEL_WIDTH_M, WHEEL_WIDTH_M), self.wheel_radius)

    @property
    def footprint_radius(self) -> float:
        """The radius of the circle around the robot's outline, wheels included (m): Nav2's
        ``robot_radius``."""
        half_x = self.wheel_base / 2 + self.wheel_radius
        half_y = self.wheel_separation / 2 + WHEEL_WIDTH_M / 2
        return math.hypot(half_x, half_y)


@dataclass(frozen=True)
class PlatformFrames:
    """The frame names a platform is published with.

    Attributes:
        footprint: the frame on the ground (None: base_link is the root, as in 2012).
        base: the chassis frame. odom, map: the odometry and map frames.
        sensor_suffix: appended to a sensor's name for its frame. lower: names in lower case.
        odom_sensor_frame: the frame name given to the odometry sensor (2012: ``odom``), or
        None for its usual name.
    """

    footprint: str | None = "base_footprint"
    base: str = "base_link"
    odom: str = "odom"
    map: str = "map"
    sensor_suffix: str = "_link"
    lower: bool = True
    odom_sensor_frame: str | None = None

    @property
    def root(self) -> str:
        """The tree's root link (the child of the odom frame)."""
        return self.footprint or self.base

    def placed(self, sensor: SensorFrame) -> bool:
        """Whether the sensor gets a fixed frame under base_link (not when it is renamed to the
        odom frame itself, as in 2012)."""
        return self.sensor(sensor) != self.odom

    def sensor(self, sensor: SensorFrame) -> str:
        """The frame of a sensor."""
        if self.odom_sensor_frame is not None and sensor.type.lower() == "odometry":
            return self.odom_sensor_frame
        name = sensor.name.lower() if self.lower else sensor.name
        return f"{name}{self.sensor_suffix}"


REP105_FRAMES = PlatformFrames()
"""REP-105: map -> odom -> base_footprint -> base_link -> sensors (the default)."""
SEED_FRAMES = PlatformFrames(footprint=None, sensor_suffix="", lower=False,
                             odom_sensor_frame="odom")
"""The 2012 usar_urdf node's names: base_link the root, each sensor under its USARSim name, the
Odometry sensor renamed ``odom``: it is the odom frame itself, so it gets no fixed frame."""
FRAME_STYLES = {"rep105": REP105_FRAMES, "seed": SEED_FRAMES}


def mount_matrix(sensor: SensorFrame) -> Array:
    """A sensor's mount in base_link as a 4x4 matrix (m)."""
    return transform_from_xyz_rpy(sensor.xyz, sensor.rpy)
