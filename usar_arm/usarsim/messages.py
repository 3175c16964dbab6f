"""One frozen dataclass per USARSim line type this project sends or receives.

Field names follow the protocol keys (``max_torque`` for ``{MaxTorque ..}``). Units are the wire's:
metres and radians in the USARSim z-down frame, seconds of simulated time. Keys a dataclass does
not model are kept, in order, in its ``extra`` tuple so nothing a server says is dropped; a line
with an unknown command word becomes :class:`Unknown`.

Text <-> message conversion lives in :mod:`usar_arm.usarsim.codec`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

# The cell's lines (WorldController, truth extensions), re-exported with the rest.
from usar_arm.usarsim.cell_messages import ContactPair as ContactPair
from usar_arm.usarsim.cell_messages import ContactReport as ContactReport
from usar_arm.usarsim.cell_messages import Control as Control
from usar_arm.usarsim.cell_messages import GripTruth as GripTruth
from usar_arm.usarsim.cell_messages import WcObjectStatus as WcObjectStatus
from usar_arm.usarsim.cell_messages import WcStatus as WcStatus

Vector3 = tuple[float, float, float]
Block = tuple[str, str]
"""A ``{Key value}`` block: key and value text (value is ``""`` for a bare ``{On}``)."""


# ----------------------------------------------------------------------- server -> client: NFO


@dataclass(frozen=True)
class GameInfo:
    """``NFO {Gametype g} {Level m} {TimeLimit t}``, sent on connect."""

    gametype: str
    level: str
    time_limit: float | None = None
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class StartPose:
    """A named spawn pose: location (m) and roll, pitch, yaw (rad), z-down frame."""

    name: str
    location: Vector3
    rotation: Vector3


@dataclass(frozen=True)
class StartPoses:
    """``NFO {StartPoses N} {Name1 x,y,z r,p,y Name2 ...}``, the reply to GETSTARTPOSES."""

    poses: tuple[StartPose, ...]

    @property
    def names(self) -> tuple[str, ...]:
        """The start names, in the server's order."""
        return tuple(p.name for p in self.poses)


# ----------------------------------------------------------------------- client -> server


@dataclass(frozen=True)
class GetStartPoses:
    """``GETSTARTPOSES``."""


@dataclass(frozen=True)
class Init:
    """``INIT {ClassName pkg.Class} {Name n} ({Start tag} | {Location x,y,z} {Rotation r,p,y})``.

    The server sends no reply; the robot appears asynchronously.
    """

    class_name: str
    name: str | None = None
    start: str | None = None
    location: Vector3 | None = None
    rotation: Vector3 | None = None
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class GetConf:
    """``GETCONF {Type T} [{Name n}]``. No reply at all when nothing matches."""

    type: str
    name: str | None = None


@dataclass(frozen=True)
class GetGeo:
    """``GETGEO {Type T} [{Name n}]``. No reply at all when nothing matches."""

    type: str
    name: str | None = None


@dataclass(frozen=True)
class Act:
    """``ACT {Name actuator} {Link i} {Value v} ...``: joint targets, **0-based** link indices.

    Values are radians (revolute) or metres (prismatic). Only ``Link`` blocks immediately
    followed by a ``Value`` block count, and both keys are case-sensitive, as in UDK.
    """

    name: str
    targets: tuple[tuple[int, float], ...]
    gripper: int | None = None
    sequence: int | None = None
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class Set:
    """``SET {Type T} {Name n} {Opcode op} [{Params p}]``."""

    type: str
    name: str
    opcode: str
    params: str | None = None


@dataclass(frozen=True)
class Drive:
    """``DRIVE ...`` (ground vehicles; the arm tools never send it; docs/protocol.md 9, 10).

    A skid-steered vehicle reads ``{Left l} {Right r}`` (wheel spins, rad/s), an
    Ackermann-steered one ``{Speed s} {FrontSteer a} {RearSteer b}`` (one wheel spin in rad/s,
    steer angles in rad, positive turning right); with ``{Normalized true}`` spins are percent
    of each wheel's MaxVelocity. Each vehicle ignores the other's keys.
    """

    left: float | None = None
    right: float | None = None
    normalized: bool | None = None
    light: bool | None = None
    extra: tuple[Block, ...] = ()
    speed: float | None = None
    front_steer: float | None = None
    rear_steer: float | None = None


# ----------------------------------------------------------------------- CONF / GEO replies


@dataclass(frozen=True)
class LinkConf:
    """One ``{Link i} {JointType ..} {MaxTorque ..} {MinValue ..} {MaxValue ..}`` group.

    ``link`` is 1-based. ``max_speed`` is only sent by UT-era servers.
    """

    link: int
    joint_type: str
    max_torque: float | None = None
    min_value: float | None = None
    max_value: float | None = None
    max_speed: float | None = None
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class ConfItem:
    """One component in a CONF reply: its name, scalar fields, and per-link groups."""

    name: str
    fields: tuple[Block, ...] = ()
    links: tuple[LinkConf, ...] = ()

    def get(self, key: str) -> str | None:
        """The value of a field, matching the key case-insensitively."""
        for k, v in self.fields:
            if k.lower() == key.lower():
                return v
        return None


@dataclass(frozen=True)
class Conf:
    """``CONF {Type T} {Name a} ... {Name b} ...``: the reply to ``GETCONF {Type T}``."""

    type: str
    items: tuple[ConfItem, ...]


@dataclass(frozen=True)
class PlatformConf:
    """``CONF {Name KR60} {Type StaticPlatform} {SteeringType None} {Mass 0}``.

    The reply to ``GETCONF {Type Robot}``; note that Name comes before Type here.
    """

    name: str
    type: str
    fields: tuple[Block, ...] = ()


@dataclass(frozen=True)
class LinkGeo:
    """One ``{Link i} {Parent p} {Location x,y,z} {Orientation r,p,y}`` group of an actuator GEO.

    ``parent`` is the 1-based link whose child part carries this joint (0: the actuator base).
    ``location`` is the offset from the parent joint in the **actuator base frame**;
    ``orientation`` is the rotation relative to the parent joint's frame.
    """

    link: int
    parent: int
    location: Vector3
    orientation: Vector3
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class GeoItem:
    """One component in a GEO reply.

    For an actuator: its mount pose relative to the platform (or to ``mount_link`` of another
    actuator), its links, and the ``tip`` offset. For a sensor: its mount pose.
    """

    name: str
    location: Vector3 | None = None
    orientation: Vector3 | None = None
    mount: str | None = None
    mount_link: int | None = None
    links: tuple[LinkGeo, ...] = ()
    tip: Vector3 | None = None
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class Geo:
    """``GEO {Type T} {Name a} ...``: the reply to ``GETGEO {Type T}``."""

    type: str
    items: tuple[GeoItem, ...]


# ----------------------------------------------------------------------- streams


@dataclass(frozen=True)
class Asta:
    """``ASTA {Time t} {Name arm} {Link 1} {Value q1} ...``: joint values, **1-based** links."""

    time: float
    name: str
    values: tuple[tuple[int, float], ...]
    extra: tuple[Block, ...] = ()

    def positions(self) -> tuple[float, ...]:
        """The joint values ordered by link index."""
        return tuple(v for _, v in sorted(self.values))

    def joints(self, links: tuple[int, ...]) -> tuple[float, ...] | None:
        """The values (rad or m) of ``links`` (1-based), in that order: one arm's joint vector
        in its configuration order; None when the line lacks any of them (a partial line, or
        another actuator's)."""
        values = dict(self.values)
        if not all(k in values for k in links):
            return None
        return tuple(values[k] for k in links)


@dataclass(frozen=True)
class Sta:
    """``STA {Time t} {Battery b} {Type StaticPlatform} ...``: platform status."""

    time: float
    battery: int | None = None
    type: str | None = None
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class Sen:
    """``SEN [{Time t}] {Type T} {Name n} ...``; GroundTruth adds Location and Orientation."""

    type: str
    name: str
    time: float | None = None
    location: Vector3 | None = None
    orientation: Vector3 | None = None
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class RangeScan:
    """``SEN {Time t} {Type RangeScanner} {Name n} {Resolution r} {FOV f} {Range r1,r2,...}``.

    A laser scan (RangeScanner.uc): ``resolution`` and ``fov`` in radians, ``ranges`` in metres
    from the scanner's right (+FOV/2) to its left (-FOV/2). UDK prints Resolution and FOV with
    FloatString (4 decimals) and each range with FloatString(r, 2), truncated.
    """

    name: str
    resolution: float
    fov: float
    ranges: tuple[float, ...]
    time: float | None = None
    type: str = "RangeScanner"
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class Ins:
    """``SEN {Type INS} {Name n} {Location x,y,z} {Orientation r,p,y}`` (INS.uc; no Time in UDK).

    The estimated pose of the platform in the world (m, z down; roll, pitch, yaw in [0, 2 pi)),
    printed as raw engine vectors (2 decimals).
    """

    name: str
    location: Vector3
    orientation: Vector3
    time: float | None = None
    type: str = "INS"
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class Odometry:
    """``SEN {Time t} {Type Odometry} {Name n} {Pose x,y,theta}`` (Odometry.uc).

    The wheel odometry of a skid-steered vehicle: x, y (m) and heading theta (rad) integrated
    from the front wheels' spin since the sensor started (or its last RESET), in the frame the
    vehicle had then.
    """

    name: str
    pose: Vector3
    time: float | None = None
    type: str = "Odometry"
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class Eff:
    """``EFF {Time t} {Type T} {Name n} {On}|{Off}|{Status ..}``: effector status."""

    type: str
    name: str
    time: float | None = None
    extra: tuple[Block, ...] = ()

    def get(self, key: str) -> str | None:
        """The value of a data block (``Status``, ``ToolType``, ``Tool``), any case."""
        return next((v for k, v in self.extra if k.lower() == key.lower()), None)

    @property
    def status(self) -> str | None:
        """``OPEN`` or ``CLOSED`` (upper case), None for an effector without a Status."""
        value = self.get("Status")
        return None if value is None else value.upper()


# ----------------------------------------------------------------------- anything else


@dataclass(frozen=True)
class Unknown:
    """A line whose command word this project does not model, kept whole."""

    head: str
    blocks: tuple[Block, ...] = field(default_factory=tuple)


Message = (
    GameInfo | StartPoses | GetStartPoses | Init | GetConf | GetGeo | Act | Set | Drive | Conf
    | PlatformConf | Geo | Asta | Sta | Sen | RangeScan | Ins | Odometry | Eff | Unknown
    | Control | WcStatus | ContactReport | GripTruth
)
