"""Learn a ground vehicle over the wire: its CONF/GEO, then each sensor's CONF/GEO.

1. spawn it (:func:`~usar_arm.discover.interview.spawn_robot`) and listen to its SEN lines for
   :data:`LISTEN_S` s to learn which sensors it carries (``Type Name``);
2. ``GETCONF``/``GETGEO {Type Robot}``: steering type, mass, wheel speed limit, wheel radius,
   separation and base (UDK's WheeledVehicle.uc);
3. ``GETCONF``/``GETGEO {Type T} {Name n}`` for each sensor of a known type: its scan interval,
   a scanner's range and angles, its mount on the chassis. A sensor whose GETGEO gets no answer
   is *hidden*; a sensor of a type not in :data:`KNOWN_SENSOR_TYPES` is *unknown*: both are
   reported (logged, and listed in the description), never guessed.

Mounts arrive in USARSim's z-down frame and are converted to REP-103 with the same conversion
the arm's discovery uses (:func:`usar_arm.core.spatial.zdown_to_zup_transform`).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

from usar_arm.core.errors import DescriptionError, ResponseTimeoutError
from usar_arm.core.platform import (
    ACKERMANN_STEERED,
    SUPPORTED_STEERING,
    PlatformDescription,
    Scanner,
    SensorFrame,
    Wheel,
)
from usar_arm.core.spatial import matrix_to_rpy, transform_from_xyz_rpy, zdown_to_zup_transform
from usar_arm.core.vehicle_errors import NotAVehicleError, UnsupportedSteeringError
from usar_arm.discover.interview import Ask, DiscoveryRecord, spawn_robot
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient

log = logging.getLogger("usar_arm.discover")

LISTEN_S = 0.6
"""How long to listen to the SEN lines after the spawn (s): more than the slowest shipped
sensor's 0.2 s scan interval, twice."""
SENSOR_GEO_TIMEOUT_S = 1.0
"""How long a sensor's GETGEO may stay unanswered before the sensor counts as hidden (s)."""
KNOWN_SENSOR_TYPES = ("GroundTruth", "INS", "Odometry", "RangeScanner")
"""The sensor types usar-arm describes (and the platform node serves)."""
GROUND_VEHICLE = "GroundVehicle"
NO_STEER_RANGE = 6.28
"""The steer range (rad) UDK reports for wheels no joint steers: its search's start value."""


@dataclass(frozen=True)
class SensorReply:
    """What the wire said about one sensor: its type and name, its CONF item and GEO item
    (None when no reply came)."""

    type: str
    name: str
    conf: m.ConfItem | None
    geo: m.GeoItem | None


def _number(fields: tuple[m.Block, ...], key: str, what: str) -> float:
    for k, v in fields:
        if k.lower() == key.lower():
            try:
                value = float(v)
            except ValueError:
                break
            if math.isfinite(value):
                return value
            break
    raise DescriptionError(f"{what}: expected a finite number in {{{key} ..}}, got "
                           f"{dict(fields).get(key, 'nothing')!r}")


def _optional(item: m.ConfItem | None, key: str) -> float | None:
    text = item.get(key) if item is not None else None
    try:
        value = float(text) if text is not None else None
    except ValueError:
        return None
    return value if value is not None and math.isfinite(value) else None


def _mount(geo: m.GeoItem) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """A sensor's mount (z-down, chassis frame) as REP-103 xyz (m) and rpy (rad)."""
    zdown = transform_from_xyz_rpy(geo.location or (0.0, 0.0, 0.0),
                                   geo.orientation or (0.0, 0.0, 0.0))
    zup = zdown_to_zup_transform(zdown)
    xyz = tuple(float(v) + 0.0 for v in zup[:3, 3])
    rpy = tuple(float(v) + 0.0 for v in matrix_to_rpy(zup[:3, :3]))
    return (xyz[0], xyz[1], xyz[2]), (rpy[0], rpy[1], rpy[2])


def _sensor(reply: SensorReply) -> SensorFrame:
    assert reply.geo is not None
    xyz, rpy = _mount(reply.geo)
    scanner = None
    if reply.type.lower() == "rangescanner":
        what = f"range scanner {reply.name}"
        fields = reply.conf.fields if reply.conf is not None else ()
        scanner = Scanner(_number(fields, "MaxRange", what), _number(fields, "MinRange", what),
                          _number(fields, "Resolution", what), _number(fields, "Fov", what),
                          _optional(reply.conf, "ScanInterval"))
    return SensorFrame(reply.type, reply.name, xyz, rpy, _optional(reply.conf, "ScanInterval"),
                       scanner)


def platform_from_replies(robot_class: str, conf: m.PlatformConf, geo: m.Geo,
                          sensors: list[SensorReply], unknown: tuple[str, ...] = ()
                          ) -> PlatformDescription:
    """The description of a ground vehicle from its replies (no I/O).

    Raises:
        UnsupportedSteeringError: a steering type other than skid or Ackermann steering.
        DescriptionError: a missing or non-finite number, or no GEO for the robot.
    """
    steering = steering_type(conf, robot_class)
    front, rear = (_steer_limits(conf, robot_class) if steering == ACKERMANN_STEERED
                   else (0.0, 0.0))
    item = next((i for i in geo.items if i.name.lower() == conf.name.lower()),
                geo.items[0] if geo.items else None)
    if item is None:
        raise DescriptionError(f"{robot_class}: GETGEO {{Type Robot}} named no item; expected "
                               "{Dimensions ..} {WheelRadius ..} {WheelSeparation ..} "
                               "{WheelBase ..}")
    what = f"{robot_class} GEO"
    radius = _number(item.extra, "WheelRadius", what)
    separation = _number(item.extra, "WheelSeparation", what)
    base = _number(item.extra, "WheelBase", what)
    dims_text = dict((k.lower(), v) for k, v in item.extra).get("dimensions", "0,0,0")
    try:
        dx, dy, dz = (float(v) for v in dims_text.split(","))
    except ValueError as exc:
        raise DescriptionError(f"{what}: expected {{Dimensions x,y,z}}, got {dims_text!r}"
                               ) from exc
    if not (radius > 0 and separation > 0 and base > 0):
        raise DescriptionError(f"{what}: wheel radius, separation and base must be > 0, got "
                               f"{radius}, {separation}, {base}")
    wheels = tuple(Wheel(side, end, (sx * base / 2, sy * separation / 2, 0.0))
                   for end, sx in (("front", 1.0), ("rear", -1.0))
                   for side, sy in (("left", 1.0), ("right", -1.0)))
    placed = [r for r in sensors if r.geo is not None]
    hidden = tuple(f"{r.type} {r.name}" for r in sensors if r.geo is None)
    what = f"{robot_class} CONF"
    return PlatformDescription(
        name=conf.name, robot_class=robot_class, platform_type=conf.type,
        steering_type=steering, mass=_number(conf.fields, "Mass", what),
        max_speed=_number(conf.fields, "MaxSpeed", what),
        max_torque=_number(conf.fields, "MaxTorque", what), wheel_radius=radius,
        wheel_separation=separation, wheel_base=base, dimensions=(dx, dy, dz),
        axle_height=0.0, wheels=wheels, sensors=tuple(_sensor(r) for r in placed),
        hidden=hidden, unknown=unknown, max_front_steer=front, max_rear_steer=rear,
        notes=("the wire gives no wheel height: the axles are assumed at base_link's height, "
               "base_footprint one wheel radius below it",
               "the wire gives no wheel width nor body shape: the body box spans the wheels, "
               "the wheels are drawn 0.05 m wide"))


def steering_type(conf: m.PlatformConf, robot_class: str) -> str:
    """The CONF's SteeringType, one usar-arm describes and drives.

    Raises:
        UnsupportedSteeringError: any other (or none given), in one line naming both.
    """
    fields = dict((k.lower(), v) for k, v in conf.fields)
    steering = fields.get("steeringtype", "(none given)")
    if steering not in SUPPORTED_STEERING:
        raise UnsupportedSteeringError(
            f"{robot_class} reports {{SteeringType {steering}}}: usar-arm describes and drives "
            f"only {' and '.join(SUPPORTED_STEERING)} ground vehicles")
    return steering


def _steer_limits(conf: m.PlatformConf, robot_class: str) -> tuple[float, float]:
    """The largest front and rear steer angles (rad) of an Ackermann vehicle: half the ranges
    its CONF MaxFrontSteer/MaxRearSteer reports (``AckermanSteeredVehicle.uc GetConfData``:
    LimitHigh - LimitLow of the steer joints; 6.28, its search's start, when none steers: 0
    here).

    Raises:
        DescriptionError: MaxFrontSteer or MaxRearSteer missing or not finite, or the front
            wheels do not steer (usar-arm drives front-steered vehicles).
    """
    what = f"{robot_class} CONF"
    ranges = [_number(conf.fields, key, what) for key in ("MaxFrontSteer", "MaxRearSteer")]
    front, rear = (r / 2 if 0 < r < NO_STEER_RANGE else 0.0 for r in ranges)
    if front <= 0:
        raise DescriptionError(f"{what}: {{MaxFrontSteer {ranges[0]:g}}} says the front wheels "
                               "do not steer; usar-arm drives front-steered Ackermann vehicles "
                               "(a rear-steered one, such as BasicAckermanRobot, is not)")
    return front, rear


def _sensor_names(client: UsarClient, timeout: float) -> list[str]:
    """``Type Name`` of each sensor whose SEN lines arrive within :data:`LISTEN_S` s (and up to
    ``timeout`` s more until one does)."""
    deadline = time.monotonic() + LISTEN_S
    while True:
        names = [c for c in client.known_components() if not c.startswith("Actuator ")]
        now = time.monotonic()
        if now > deadline + (timeout if not names else 0.0):
            return names
        time.sleep(0.02)


def learn_platform(client: UsarClient, robot_class: str, start: str | None = None,
                   timeout: float | None = None, known_classes: tuple[str, ...] = ()
                   ) -> tuple[DiscoveryRecord, PlatformDescription]:
    """Spawn ``robot_class`` and learn it as a ground vehicle.

    Raises:
        NotAVehicleError: the robot is not a ground vehicle (its CONF Type says what it is).
        DescriptionError: a number of the vehicle's CONF or GEO missing or not finite.
        UnsupportedSteeringError, UnknownRobotError, UnknownStartError, ConnectionLostError.
    """
    record, ask = spawn_robot(client, robot_class, None, start, timeout, known_classes)
    conf = ask(m.GetConf("Robot"), m.PlatformConf)
    assert isinstance(conf, m.PlatformConf)
    if conf.type != GROUND_VEHICLE:
        raise NotAVehicleError(record.robot_class, conf.type)
    steering_type(conf, record.robot_class)  # (refused before a sensor is asked about)
    geo = ask(m.GetGeo("Robot"), m.Geo)
    assert isinstance(geo, m.Geo)
    components = _sensor_names(client, timeout or client.timeout)
    record.components = components
    replies: list[SensorReply] = []
    unknown: list[str] = []
    for comp in components:
        kind, _, name = comp.partition(" ")
        if kind not in KNOWN_SENSOR_TYPES:
            log.warning("sensor %s of unknown type %s: not described (usar-arm knows %s)",
                        name, kind, ", ".join(KNOWN_SENSOR_TYPES))
            unknown.append(comp)
            continue
        replies.append(_ask_sensor(ask, kind, name))
    return record, platform_from_replies(record.robot_class, conf, geo, replies, tuple(unknown))


def _ask_sensor(ask: Ask, kind: str, name: str) -> SensorReply:
    """One sensor's CONF and GEO; a silence counts as nothing said (a hidden sensor)."""
    got: dict[type, m.ConfItem | m.GeoItem | None] = {}
    for request, reply in ((m.GetConf(kind, name), m.Conf), (m.GetGeo(kind, name), m.Geo)):
        try:
            msg = ask(request, reply, name, SENSOR_GEO_TIMEOUT_S)
        except ResponseTimeoutError:
            got[reply] = None
            continue
        items = getattr(msg, "items", ())
        got[reply] = next((i for i in items if i.name.lower() == name.lower()), None)
    conf, geo = got[m.Conf], got[m.Geo]
    assert conf is None or isinstance(conf, m.ConfItem)
    assert geo is None or isinstance(geo, m.GeoItem)
    if geo is None:
        log.warning("sensor %s %s: GETGEO gave nothing (a hidden sensor): no frame written",
                    kind, name)
    return SensorReply(kind, name, conf, geo)
