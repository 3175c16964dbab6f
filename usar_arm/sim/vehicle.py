"""Ground vehicles of the embedded simulator (the P3AT), in USARSim's own terms.

A vehicle is a chassis carried by wheels (``WheelJoint`` in UDK: a side, a maximum spin speed in
rad/s, driven or not) and sensors mounted on the chassis (``AddParts`` in ``DefaultUSAR.ini``).
Everything is in the USARSim protocol frame (x forward, y right, z down), metres, radians, kg.

What UDK computes from these numbers lives here too, free of the physics: how ``DRIVE`` maps to
wheel speeds (``SkidSteeredVehicle.uc Drive``, ``WheelJoint.uc SetVelocity``), the robot's CONF
and GEO (``WheeledVehicle.uc GetConfData/GetGeoData``), and the directions of a range scanner's
rays (``RangeScanner.uc GetData``, in Unreal angle units).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from usar_arm.core.errors import FileFormatError

Vec3 = tuple[float, float, float]

ANGLE_TO_UROT = 10430.3783505
"""Unreal rotation units per radian (``C_AngleToURot``, 65536 / 2 pi)."""
DRIVE_LIMIT_PERCENT = 100.0
"""A normalized DRIVE speed is a percentage of the wheel's MaxVelocity."""
UDK_MAX_SPEED = 100.0
"""``WheeledVehicle.uc GetConfData`` starts its search for the lowest MaxVelocity here."""
UDK_MAX_TORQUE = 50000.0
"""... and for the lowest wheel MaxForce here."""
SKID = "SkidSteered"
ACKERMANN = "AckermanSteered"
"""The steering types of UDK's wheeled vehicles (``GetSteeringType``; Ackerman with one n)."""
NO_STEER_RANGE = 6.28
"""``AckermanSteeredVehicle.uc GetConfData`` starts its search for the smallest steer range here
(rad): what it reports when no joint steers."""


@dataclass(frozen=True)
class Box:
    """A box-shaped rigid piece of the chassis: centre (m, chassis frame), half sizes (m), mass."""

    name: str
    center: Vec3
    half: Vec3
    mass: float


@dataclass(frozen=True)
class SteerSpec:
    """The revolute joint that steers a wheel (``RevoluteJoint`` between the chassis and the
    part the wheel's joint hangs on, ``AckermanSteeredVehicle.uc``).

    Attributes:
        name: the joint's name. end: ``front`` or ``rear``: which DRIVE angle moves it (UDK
            looks for ``FRONTSTEER`` or ``REARSTEER`` in the name, any case; :func:`steer_end`).
        limit_low, limit_high: its range (rad; targets are clamped into it).
        mass: the part it turns (the hidden ``EmptyMesh``, kg). damping: ``Damping``.
    """

    name: str
    end: str
    limit_low: float
    limit_high: float
    mass: float
    damping: float
    max_force: float = UDK_MAX_TORQUE


def steer_end(joint: str) -> str:
    """``front``, ``rear`` or ``""`` (no DRIVE angle moves it) for a steer joint's name."""
    upper = joint.upper()
    return "front" if "FRONTSTEER" in upper else "rear" if "REARSTEER" in upper else ""


@dataclass(frozen=True)
class WheelSpec:
    """A wheel (``WheelJoint``): its part, side, anchor on the chassis and limits.

    Attributes:
        offset: wheel centre in the chassis frame (m).
        max_velocity: the highest spin speed a DRIVE can ask for (rad/s, ``MaxVelocity``).
        max_force: the drive's torque limit (``MaxForce``; UDK's default 50000).
        steer: the joint that steers it (None: fixed to the chassis).
    """

    name: str
    side: str
    offset: Vec3
    mass: float
    max_velocity: float
    max_force: float = UDK_MAX_TORQUE
    driven: bool = True
    steer: SteerSpec | None = None


@dataclass(frozen=True)
class SensorMount:
    """A sensor fixed to the chassis (``AddParts``): its class, name, pose and settings.

    ``settings`` holds the ``[USARSensor.<class>]`` values that apply (ScanInterval, MaxRange...).
    """

    type: str
    name: str
    position: Vec3
    direction: Vec3
    settings: tuple[tuple[str, float], ...] = ()

    def setting(self, key: str, default: float) -> float:
        """A numeric setting of the sensor (``default`` when the config does not set it)."""
        return next((v for k, v in self.settings if k == key), default)


@dataclass(frozen=True)
class VehicleSpec:
    """A wheeled ground vehicle, skid- or Ackermann-steered: chassis boxes, wheels, sensors.

    Attributes:
        wheel_radius: ``WheelRadius`` (m); also the radius of the wheels' contact spheres.
        wheel_width: half width of a wheel (m), for drawing; the .uc has only meshes.
        extra_masses: parts that ride on the chassis without a shape of their own (bumpers).
    """

    steering_type: str
    wheel_radius: float
    wheel_width: float
    chassis: tuple[Box, ...]
    extra_masses: tuple[tuple[str, Vec3, float], ...]
    wheels: tuple[WheelSpec, ...]
    sensors: tuple[SensorMount, ...]

    @property
    def mass(self) -> float:
        """Sum of the part masses (kg) in float32, as ``USARVehicle.uc GetMass`` adds them."""
        total = np.float32(0.0)
        for m in [b.mass for b in self.chassis] + [w.mass for w in self.wheels] + [
                e[2] for e in self.extra_masses] + [
                w.steer.mass for w in self.wheels if w.steer is not None]:
            total = np.float32(total + np.float32(m))
        return float(total)

    @property
    def rest_height(self) -> float:
        """Height (m) of the chassis origin above flat ground with the wheels on it."""
        return max(w.offset[2] for w in self.wheels) + self.wheel_radius

    def corner_wheels(self) -> tuple[WheelSpec, WheelSpec]:
        """The front left and rear right wheels (``WheeledVehicle.uc GetGeoData``)."""
        left = max((w for w in self.wheels if w.side == "Left"), key=lambda w: w.offset[0])
        right = min((w for w in self.wheels if w.side == "Right"), key=lambda w: w.offset[0])
        return left, right

    def front_wheels(self) -> tuple[WheelSpec, WheelSpec]:
        """The front left and front right wheels (``Odometry.uc FindTires``)."""
        left = max((w for w in self.wheels if w.side == "Left"), key=lambda w: w.offset[0])
        right = max((w for w in self.wheels if w.side == "Right"), key=lambda w: w.offset[0])
        return left, right

    @property
    def max_speed(self) -> float:
        """The lowest wheel MaxVelocity (rad/s), as CONF MaxSpeed reports it."""
        return min([UDK_MAX_SPEED] + [w.max_velocity for w in self.wheels])

    @property
    def max_torque(self) -> float:
        """The lowest wheel MaxForce, as CONF MaxTorque reports it."""
        return min([UDK_MAX_TORQUE] + [w.max_force for w in self.wheels])

    @property
    def ackermann(self) -> bool:
        """Whether DRIVE steers the wheels (``AckermanSteered``) instead of driving two sides."""
        return self.steering_type == ACKERMANN

    def steers(self, end: str) -> tuple[SteerSpec, ...]:
        """The steer joints a DRIVE angle moves: ``end`` is ``front`` or ``rear``."""
        return tuple(w.steer for w in self.wheels if w.steer is not None and w.steer.end == end)

    def steer_range(self, end: str) -> float:
        """The smallest range (rad) of the ``end``'s steer joints, in float32, as CONF
        MaxFrontSteer/MaxRearSteer reports it (``AckermanSteeredVehicle.uc GetConfData``:
        6.28 when none steers)."""
        f32 = np.float32
        ranges = [float(abs(f32(s.limit_high) - f32(s.limit_low))) for s in self.steers(end)]
        return min([float(f32(NO_STEER_RANGE)), *ranges])

    def sensors_of(self, type_: str) -> tuple[SensorMount, ...]:
        """The mounted sensors of a type (case-insensitive, as ``Item.uc IsType``)."""
        return tuple(s for s in self.sensors if s.type.upper() == type_.upper())


@dataclass(frozen=True)
class WheelCommand:
    """What a DRIVE asks of the wheels: speeds (rad/s, per wheel name) and what was clamped."""

    speeds: dict[str, float]
    clamped: tuple[str, ...]


def drive_wheels(spec: VehicleSpec, left: float, right: float, normalized: bool,
                 sides: tuple[str, ...] = ("Left", "Right")) -> WheelCommand:
    """Wheel speeds for ``DRIVE {Left left} {Right right}`` (SkidSteeredVehicle.uc Drive).

    Normalized speeds are percentages of each wheel's MaxVelocity; every driven wheel of
    ``sides`` takes its side's speed (``right`` for a wheel of no side), clamped to
    +-MaxVelocity (WheelJoint.uc SetVelocity). Positive is forward.
    """
    speeds: dict[str, float] = {}
    clamped: list[str] = []
    for w in spec.wheels:
        if not w.driven or w.side not in sides:
            continue
        asked = left if w.side == "Left" else right
        if normalized:
            asked = asked * w.max_velocity / DRIVE_LIMIT_PERCENT
        speed = min(w.max_velocity, max(-w.max_velocity, asked))
        if speed != asked:
            clamped.append(w.name)
        speeds[w.name] = speed
    return WheelCommand(speeds, tuple(clamped))


@dataclass(frozen=True)
class SteerCommand:
    """What an Ackermann DRIVE asks: the wheels' spins and each steer joint's target (rad,
    clamped into its limits), and the names of what was clamped."""

    wheels: WheelCommand
    targets: dict[str, float]
    clamped: tuple[str, ...]


def drive_ackermann(spec: VehicleSpec, speed: float, front: float, rear: float,
                    normalized: bool) -> SteerCommand:
    """Wheel spins and steer targets for ``DRIVE {Speed speed} {FrontSteer front} {RearSteer
    rear}`` (``AckermanSteeredVehicle.uc Drive``).

    Every driven wheel takes ``speed`` (rad/s; normalized: percent of its own MaxVelocity),
    clamped to +-MaxVelocity (``WheelJoint.uc SetVelocity``); every steer joint takes its end's
    angle (rad, positive turning right about z down), clamped into its limits
    (``RevoluteJoint.uc SetTarget``).
    """
    wheels = drive_wheels(spec, speed, speed, normalized, sides=("Left", "Right", "None"))
    targets: dict[str, float] = {}
    clamped: list[str] = []
    for w in spec.wheels:
        if w.steer is None or not w.steer.end:
            continue
        asked = front if w.steer.end == "front" else rear
        targets[w.steer.name] = min(w.steer.limit_high, max(w.steer.limit_low, asked))
        if targets[w.steer.name] != asked:
            clamped.append(w.steer.name)
    return SteerCommand(wheels, targets, tuple(clamped))


def scan_yaws(resolution: float, fov: float) -> tuple[np.ndarray, float, float]:
    """The yaw (rad, positive to the right) of every ray of a scan, and the Resolution and FOV
    the scanner reports, as ``RangeScanner.uc GetData`` steps them in integer Unreal units:
    from ``int(FOV/2)`` down to ``-FOV/2`` by ``Resolution``.
    """
    res_uu = int(resolution * ANGLE_TO_UROT)
    fov_uu = int(fov * ANGLE_TO_UROT)
    if res_uu <= 0:
        raise ValueError(f"scanner resolution {resolution} rad is below one Unreal unit")
    steps = []
    i = int(fov_uu / 2)
    while i >= -fov_uu / 2:
        steps.append(i)
        i -= res_uu
    return np.asarray(steps, dtype=float) / ANGLE_TO_UROT, res_uu / ANGLE_TO_UROT, \
        fov_uu / ANGLE_TO_UROT


# ------------------------------------------------------------------------------- loading


def _vec(value: Any, path: str, field: str) -> Vec3:
    if not (isinstance(value, list) and len(value) == 3):
        raise FileFormatError(path, f"expected [x, y, z], got {value!r}", field=field)
    try:
        out = (float(value[0]), float(value[1]), float(value[2]))
    except (TypeError, ValueError):
        raise FileFormatError(path, f"expected three numbers, got {value!r}", field=field) from None
    if not all(math.isfinite(v) for v in out):
        raise FileFormatError(path, f"expected finite numbers, got {value!r}", field=field)
    return out


def _number(d: dict[str, Any], key: str, path: str, where: str) -> float:
    if key not in d:
        raise FileFormatError(path, f"missing '{key}'", field=f"{where}.{key}")
    try:
        return float(d[key])
    except (TypeError, ValueError):
        raise FileFormatError(path, f"expected a number, got {d[key]!r}",
                              field=f"{where}.{key}") from None


def load_vehicle(d: dict[str, Any], path: str) -> VehicleSpec:
    """The ``vehicle:`` section of a robot file."""
    chassis = tuple(Box(str(b["name"]), _vec(b["center"], path, f"vehicle.chassis[{i}].center"),
                        _vec(b["half"], path, f"vehicle.chassis[{i}].half"),
                        _number(b, "mass", path, f"vehicle.chassis[{i}]"))
                    for i, b in enumerate(d.get("chassis", [])))
    extra = tuple((str(e["name"]), _vec(e["offset"], path, f"vehicle.extra_masses[{i}].offset"),
                   _number(e, "mass", path, f"vehicle.extra_masses[{i}]"))
                  for i, e in enumerate(d.get("extra_masses", [])))
    wheels = []
    for i, w in enumerate(d.get("wheels", [])):
        where = f"vehicle.wheels[{i}]"
        side = str(w.get("side", "None"))
        if side not in ("Left", "Right", "None"):
            raise FileFormatError(path, f"side must be Left, Right or None, got {side}",
                                  field=f"{where}.side")
        wheels.append(WheelSpec(str(w["name"]), side, _vec(w["offset"], path, f"{where}.offset"),
                                _number(w, "mass", path, where),
                                _number(w, "max_velocity", path, where),
                                float(w.get("max_force", UDK_MAX_TORQUE)),
                                bool(w.get("driven", True)),
                                _steer(w["steer"], path, f"{where}.steer") if "steer" in w
                                else None))
    if not any(w.side == "Left" for w in wheels) or not any(w.side == "Right" for w in wheels):
        raise FileFormatError(path, "a skid-steered vehicle needs wheels on both sides",
                              field="vehicle.wheels")
    sensors = tuple(SensorMount(str(s["type"]), str(s["name"]),
                                _vec(s.get("position", [0, 0, 0]), path,
                                     f"vehicle.sensors[{i}].position"),
                                _vec(s.get("direction", [0, 0, 0]), path,
                                     f"vehicle.sensors[{i}].direction"),
                                tuple((str(k), float(v))
                                      for k, v in (s.get("settings") or {}).items()))
                    for i, s in enumerate(d.get("sensors", [])))
    steering = str(d.get("steering_type", SKID))
    if steering not in (SKID, ACKERMANN):
        raise FileFormatError(path, f"steering type {steering} is not supported (only {SKID} "
                              f"and {ACKERMANN})", field="vehicle.steering_type")
    if (steering == ACKERMANN) != any(w.steer is not None for w in wheels):
        raise FileFormatError(path, f"a vehicle steers its wheels (a steer: on a wheel) if and "
                              f"only if it is {ACKERMANN}", field="vehicle.wheels")
    return VehicleSpec(steering, _number(d, "wheel_radius", path, "vehicle"),
                       float(d.get("wheel_width", 0.05)), chassis, extra, tuple(wheels), sensors)


def _steer(d: Any, path: str, where: str) -> SteerSpec:
    """A wheel's ``steer:`` mapping (the revolute joint it hangs on)."""
    if not isinstance(d, dict) or "name" not in d:
        raise FileFormatError(path, f"expected a mapping with a name, got {d!r}", field=where)
    steer = SteerSpec(str(d["name"]), steer_end(str(d["name"])),
                      _number(d, "limit_low", path, where),
                      _number(d, "limit_high", path, where), _number(d, "mass", path, where),
                      _number(d, "damping", path, where),
                      float(d.get("max_force", UDK_MAX_TORQUE)))
    if not steer.end or not steer.limit_low <= 0 <= steer.limit_high or not steer.mass > 0:
        raise FileFormatError(path, f"steer joint {steer.name}: its name must hold FrontSteer "
                              "or RearSteer, its limits enclose 0, its mass be > 0", field=where)
    return steer
