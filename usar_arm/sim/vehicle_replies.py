"""What a spawned ground vehicle says about itself: CONF, GEO and STA, as UDK prints them.

* ``GETCONF {Type Robot}`` -> ``CONF {Name P3AT} {Type GroundVehicle} {SteeringType SkidSteered}
  {Mass ..} {MaxSpeed ..} {MaxTorque ..} {MaxFrontSteer 0} {MaxRearSteer 0}`` (BaseVehicle.uc,
  WheeledVehicle.uc, SkidSteeredVehicle.uc GetConfData; Name is the class, FloatString numbers).
* ``GETGEO {Type Robot}`` -> ``GEO {Type GroundVehicle} {Name P3AT} {Dimensions x,y,z} {COG x,y,z}
  {WheelRadius r} {WheelSeparation s} {WheelBase b}`` (WheeledVehicle.uc GetGeoData: the
  dimensions are the front left and rear right wheels' offsets apart).
* ``GETCONF``/``GETGEO {Type T}`` for a sensor type: one group per mounted sensor of that type
  (Item.uc, Sensor.uc, RangeSensor.uc, RangeScanner.uc, INS.uc, Odometry.uc, GroundTruth.uc).
  ``{Type GroundVehicle}`` matches no item, so UDK (and this simulator) send nothing.
* ``STA {Time t} {Battery b} {Type GroundVehicle} {LightToggle ..} {LightIntensity 100}
  {FrontSteer 0} {RearSteer 0}`` (USARVehicle, WheeledVehicle, SkidSteeredVehicle GetStatus).
* An Ackermann vehicle (AckermanSteeredVehicle.uc) reports ``{SteeringType AckermanSteered}``,
  its steer joints' ranges as MaxFrontSteer/MaxRearSteer, and its last DRIVE's angles in STA
  (docs/protocol.md section 10).
"""

from __future__ import annotations

import numpy as np

from usar_arm.sim.robot_spec import RobotSpec
from usar_arm.sim.vehicle import SensorMount, VehicleSpec, scan_yaws
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import NumberStyle


def _f32_diff(a: float, b: float) -> float:
    return float(np.float32(np.float32(a) - np.float32(b)))


def robot_conf(spec: RobotSpec, veh: VehicleSpec, style: NumberStyle) -> m.PlatformConf:
    """The reply to ``GETCONF {Type Robot}``."""
    f4 = lambda v: style.fixed_at(v, 4)  # noqa: E731
    return m.PlatformConf(spec.short_name, spec.platform_type, (
        ("SteeringType", veh.steering_type), ("Mass", f4(veh.mass)),
        ("MaxSpeed", f4(veh.max_speed)), ("MaxTorque", f4(veh.max_torque)),
        *_steer_ranges(veh, style)))


def _steer_ranges(veh: VehicleSpec, style: NumberStyle) -> tuple[m.Block, m.Block]:
    """``{MaxFrontSteer ..} {MaxRearSteer ..}``: 0 on a skid-steered vehicle
    (SkidSteeredVehicle.uc); an Ackermann one's steer ranges, FloatString
    (AckermanSteeredVehicle.uc GetConfData)."""
    if not veh.ackermann:
        return ("MaxFrontSteer", "0"), ("MaxRearSteer", "0")
    return (("MaxFrontSteer", style.fixed_at(veh.steer_range("front"), 4)),
            ("MaxRearSteer", style.fixed_at(veh.steer_range("rear"), 4)))


def robot_geo(spec: RobotSpec, veh: VehicleSpec, style: NumberStyle) -> m.Geo:
    """The reply to ``GETGEO {Type Robot}``."""
    left, right = veh.corner_wheels()
    base = _f32_diff(left.offset[0], right.offset[0])
    separation = _f32_diff(right.offset[1], left.offset[1])
    f4 = lambda v: style.fixed_at(v, 4)  # noqa: E731
    return m.Geo(spec.platform_type, (m.GeoItem(spec.short_name, extra=(
        ("Dimensions", ",".join(f4(v) for v in (base, separation, 0.0))),
        ("COG", ",".join(f4(v) for v in (0.0, 0.0, 0.0))),
        ("WheelRadius", f4(veh.wheel_radius)), ("WheelSeparation", f4(separation)),
        ("WheelBase", f4(base)))),))


def _sensor_conf(mount: SensorMount, style: NumberStyle) -> m.ConfItem:
    interval = ("ScanInterval", style.scalar(mount.setting("ScanInterval", 0.1)))
    if mount.type.upper() != "RANGESCANNER":
        return m.ConfItem(mount.name, (interval,))
    f4 = lambda v: style.fixed_at(v, 4)  # noqa: E731
    _, resolution, fov = scan_yaws(mount.setting("Resolution", 0.157),
                                   mount.setting("ScanFov", 3.14))
    return m.ConfItem(mount.name, (
        ("MaxRange", f4(mount.setting("MaxRange", 4.0))),
        ("MinRange", f4(mount.setting("MinRange", 0.1))),
        ("Resolution", f4(resolution)), ("Fov", f4(fov)), ("Panning", "True"),
        ("Tilting", "False")))


def sensor_conf(spec: RobotSpec, veh: VehicleSpec, type_: str, name: str | None,
                style: NumberStyle) -> m.Conf | None:
    """The reply to ``GETCONF {Type type_} [{Name name}]`` for a vehicle's sensors, or None."""
    items = [_sensor_conf(s, style) for s in veh.sensors_of(type_) if _matches(s.name, name)]
    return m.Conf(type_, tuple(items)) if items else None


def sensor_geo(spec: RobotSpec, veh: VehicleSpec, type_: str, name: str | None) -> m.Geo | None:
    """The reply to ``GETGEO {Type type_} [{Name name}]``: each sensor's mount on the chassis."""
    items = [m.GeoItem(s.name, s.position, s.direction, mount=spec.short_name)
             for s in veh.sensors_of(type_) if _matches(s.name, name)]
    return m.Geo(type_, tuple(items)) if items else None


def status(spec: RobotSpec, t: float, light: bool, angles: tuple[str, str] = ("0", "0")
           ) -> m.Sta:
    """The vehicle's STA line; ``angles``: FrontSteer and RearSteer as printed (an Ackermann
    vehicle's last DRIVE angles, FloatString: AckermanSteeredVehicle.uc GetStatus; else 0)."""
    return m.Sta(t, spec.battery, spec.platform_type, (
        ("LightToggle", "True" if light else "False"), ("LightIntensity", "100"),
        ("FrontSteer", angles[0]), ("RearSteer", angles[1])))


def _matches(item_name: str, wanted: str | None) -> bool:
    return wanted is None or wanted == "" or item_name.upper() == wanted.upper()
