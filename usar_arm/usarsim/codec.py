"""Pure text <-> message conversion for the USARSim UDK protocol, driven by one table.

Grammar (docs/protocol.md): ``COMMAND {Key value} {Key value} ...`` + CRLF. The command word is
the text before the first ``{`` and is matched case-insensitively. Each block is split at its
first whitespace into key and value; the value may contain spaces and commas and is trimmed.
Blocks may touch (``}{Mount``). Keys are matched case-insensitively, except ``Link`` and
``Value`` in ACT, which UDK compares case-sensitively. Vectors are ``x,y,z``. Numbers must be
finite: ``nan`` and ``inf``, which Python's ``float`` accepts, are refused (no USARSim server
prints them, and they would poison joint values and limits downstream).

:data:`SPECS` holds every message's wire form once: its command word and either its keyed fields
(key, attribute, kind, required or not; both directions are generated from them) or, for the
five messages with a richer structure, the parse and format pair in :mod:`.compound`.
:func:`parse_line` raises :class:`~usar_arm.core.errors.ProtocolError` quoting the line and the
column of the problem. :func:`format_message` prints numbers in a :class:`NumberStyle` (default:
full float64 precision, so ``parse_line(format_message(m)) == m``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, cast

from usar_arm.usarsim import cell_codec as cc
from usar_arm.usarsim import compound as c
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.blocks import (
    CRLF,
    MAX_LINE_BYTES,
    BlockReader,
    RawBlock,
    block,
    blocks,
    line,
    split_line,
)
from usar_arm.usarsim.numbers import FULL, NumberStyle

__all__ = ["CRLF", "MAX_LINE_BYTES", "SPECS", "Field", "Kind", "MessageSpec", "RawBlock",
           "format_message", "parse_line", "split_line"]

Parse = Callable[[BlockReader], m.Message]
Format = Callable[[m.Message, NumberStyle], str]


@dataclass(frozen=True)
class Kind:
    """How one field's value reads from its block and prints into it."""

    name: str
    read: Callable[[BlockReader, RawBlock], Any]
    show: Callable[[Any, NumberStyle], str]


def _read_bool(r: BlockReader, b: RawBlock) -> bool:
    if b.value.lower() in ("true", "1"):
        return True
    if b.value.lower() in ("false", "0"):
        return False
    raise r.error(b, f"expected true or false in {{{b.key} ...}}, got '{b.value}'")


def _read_battery(r: BlockReader, b: RawBlock) -> int:
    """The battery life: an integer as UDK prints it, or a number truncated toward zero."""
    try:
        return int(b.value)
    except ValueError:
        return int(r.number(b))


TEXT = Kind("text", lambda r, b: b.value, lambda v, s: str(v))
SCALAR = Kind("scalar", BlockReader.number, lambda v, s: s.scalar(v))
"""A raw scalar (time, speed, distance): printed in the style's scalar decimals."""
RAW_VECTOR = Kind("raw vector", lambda r, b: r.vector(b), lambda v, s: s.raw_vector(v))
"""x,y,z printed as raw floats (INIT locations, rotations)."""
FIXED_VECTOR = Kind("fixed vector", lambda r, b: r.vector(b), lambda v, s: s.fixed_vector(v))
"""x,y,z printed with UnitsConverter.FloatString (sensor poses: truncated)."""
FIXED4 = Kind("fixed4", BlockReader.number, lambda v, s: s.fixed_at(v, 4))
"""A FloatString number with UDK's default precision (scanner Resolution and FOV)."""
SCALAR_VECTOR = Kind("scalar vector", lambda r, b: r.vector(b),
                     lambda v, s: ",".join(s.scalar(c) for c in v))
"""x,y,z of raw engine floats joined by commas (odometry Pose: ``xPos $ "," $ yPos ...``)."""


def _read_ranges(r: BlockReader, b: RawBlock) -> tuple[float, ...]:
    """A comma-separated list of finite numbers (a scan's ranges; empty for no rays)."""
    if not b.value:
        return ()
    return tuple(r.number(RawBlock(b.key, part.strip(), b.pos)) for part in b.value.split(","))


RANGES = Kind("ranges", _read_ranges, lambda v, s: ",".join(s.fixed_at(x, 2) for x in v))
"""r1,r2,... printed with FloatString(r, 2) each (RangeScanner.uc)."""
BOOL = Kind("bool", _read_bool, lambda v, s: str(v).lower())
TRUE_FALSE = Kind("True/False", _read_bool, lambda v, s: str(v))
"""A bool as UnrealScript prints one (``True``, ``False``)."""
BATTERY = Kind("battery", _read_battery, lambda v, s: str(v))


@dataclass(frozen=True)
class Field:
    """One ``{key value}`` block of a message.

    Attributes:
        key: the wire key (matched case-insensitively on input).
        attr: the message dataclass attribute it fills.
        kind: how its value reads and prints.
        example: for a required block, the example value its absence error quotes; None for an
            optional block (absent: ``default``; None is not printed).
        default: the value of an absent optional block.
    """

    key: str
    attr: str
    kind: Kind = TEXT
    example: str | None = None
    default: Any = None


@dataclass(frozen=True)
class MessageSpec:
    """A message's wire form: its command word and either its fields or a compound grammar.

    With ``fields``, blocks print in field order followed by the message's unknown blocks
    (``extra``, when it has them); required fields are read first, in order, so the first
    missing one is the one an error names.
    """

    head: str
    type: type
    fields: tuple[Field, ...] = ()
    extra: bool = True
    compound: tuple[Parse, Format] | None = None

    def parse(self, r: BlockReader) -> m.Message:
        """The message in ``r``'s blocks."""
        if self.compound is not None:
            return self.compound[0](r)
        values: dict[str, Any] = {}
        for f in sorted(self.fields, key=lambda f: f.example is None):
            b = r.require(f.key, f.example) if f.example is not None else r.find(f.key)
            values[f.attr] = f.default if b is None else f.kind.read(r, b)
        if self.extra:
            values["extra"] = r.extra(*(f.key for f in self.fields))
        return cast(m.Message, self.type(**values))

    def format(self, msg: m.Message, style: NumberStyle) -> str:
        """The wire text of ``msg``, CRLF-terminated."""
        if self.compound is not None:
            return self.compound[1](msg, style)
        parts = []
        for f in self.fields:
            value = getattr(msg, f.attr)
            if value is not None:
                parts.append(block(f.key, f.kind.show(value, style)))
        if self.extra:
            parts += blocks(vars(msg)["extra"])
        return line(self.head, parts)


def _fields(*fields: Field) -> tuple[Field, ...]:
    return fields


SPECS: tuple[MessageSpec, ...] = (
    MessageSpec("NFO", m.GameInfo, _fields(
        Field("Gametype", "gametype", default=""), Field("Level", "level", default=""),
        Field("TimeLimit", "time_limit", SCALAR))),
    MessageSpec("NFO", m.StartPoses, compound=(c.parse_start_poses, c.format_start_poses)),
    MessageSpec("GETSTARTPOSES", m.GetStartPoses, extra=False),
    MessageSpec("INIT", m.Init, _fields(
        Field("ClassName", "class_name", example="USARBot.KR60"), Field("Name", "name"),
        Field("Start", "start"), Field("Location", "location", RAW_VECTOR),
        Field("Rotation", "rotation", RAW_VECTOR))),
    MessageSpec("GETCONF", m.GetConf, _fields(
        Field("Type", "type", example="Actuator"), Field("Name", "name")), extra=False),
    MessageSpec("GETGEO", m.GetGeo, _fields(
        Field("Type", "type", example="Actuator"), Field("Name", "name")), extra=False),
    MessageSpec("ACT", m.Act, compound=(c.parse_act, c.format_act)),
    MessageSpec("SET", m.Set, _fields(
        Field("Type", "type", example="Gripper"), Field("Name", "name", example="gripper"),
        Field("Opcode", "opcode", example="OPEN"), Field("Params", "params")), extra=False),
    MessageSpec("DRIVE", m.Drive, _fields(
        Field("Left", "left", SCALAR), Field("Right", "right", SCALAR),
        Field("Speed", "speed", SCALAR), Field("FrontSteer", "front_steer", SCALAR),
        Field("RearSteer", "rear_steer", SCALAR),
        Field("Normalized", "normalized", BOOL), Field("Light", "light", BOOL))),
    MessageSpec("CONF", m.PlatformConf, compound=(c.parse_platform_conf, c.format_platform_conf)),
    MessageSpec("CONF", m.Conf, compound=(c.parse_conf, c.format_conf)),
    MessageSpec("GEO", m.Geo, compound=(c.parse_geo, c.format_geo)),
    MessageSpec("ASTA", m.Asta, compound=(c.parse_asta, c.format_asta)),
    MessageSpec("STA", m.Sta, _fields(
        Field("Time", "time", SCALAR, example="12.5"), Field("Battery", "battery", BATTERY),
        Field("Type", "type"))),
    MessageSpec("SEN", m.Sen, _fields(
        Field("Time", "time", SCALAR), Field("Type", "type", example="GroundTruth"),
        Field("Name", "name", example="GroundTruth"),
        Field("Location", "location", FIXED_VECTOR),
        Field("Orientation", "orientation", FIXED_VECTOR))),
    MessageSpec("SEN", m.RangeScan, _fields(
        Field("Time", "time", SCALAR), Field("Type", "type", example="RangeScanner"),
        Field("Name", "name", example="lms200"),
        Field("Resolution", "resolution", FIXED4, example="0.0174"),
        Field("FOV", "fov", FIXED4, example="3.1415"),
        Field("Range", "ranges", RANGES, example="1.25,1.30"))),
    MessageSpec("SEN", m.Ins, _fields(
        Field("Time", "time", SCALAR), Field("Type", "type", example="INS"),
        Field("Name", "name", example="InsTest"),
        Field("Location", "location", RAW_VECTOR, example="0.00,0.00,0.00"),
        Field("Orientation", "orientation", RAW_VECTOR, example="0.00,0.00,0.00"))),
    MessageSpec("SEN", m.Odometry, _fields(
        Field("Time", "time", SCALAR), Field("Type", "type", example="Odometry"),
        Field("Name", "name", example="Odometer"),
        Field("Pose", "pose", SCALAR_VECTOR, example="0.0,0.0,0.0"))),
    MessageSpec("EFF", m.Eff, compound=(cc.parse_eff, cc.format_eff)),
    MessageSpec("SEN", m.GripTruth, _fields(
        Field("Time", "time", SCALAR), Field("Type", "type", example="GripTruth"),
        Field("Name", "name", example="KR60gripper"),
        Field("Holding", "holding", TRUE_FALSE, example="False"),
        Field("Object", "object"))),
    MessageSpec("SEN", m.ContactReport, compound=(cc.parse_contact_report,
                                                  cc.format_contact_report)),
    MessageSpec("CONTROL", m.Control, _fields(
        Field("Type", "type", example="GetSTA"), Field("Name", "name"),
        Field("ClassName", "class_name"), Field("Location", "location"),
        Field("Rotation", "rotation"), Field("Scale", "scale"), Field("Physics", "physics"),
        Field("Permanent", "permanent"), Field("Memory", "memory"),
        Field("Material", "material"), Field("Start", "start"), Field("MinPos", "min_pos"),
        Field("MaxPos", "max_pos"))),
)

_BY_TYPE: dict[type, MessageSpec] = {spec.type: spec for spec in SPECS}


def _parse_nfo(r: BlockReader) -> m.Message:
    """NFO is the greeting, or, with a StartPoses block, the reply to GETSTARTPOSES."""
    kind = m.StartPoses if r.find("StartPoses") is not None else m.GameInfo
    return _BY_TYPE[kind].parse(r)


def _parse_conf(r: BlockReader) -> m.Message:
    """A CONF is the platform's when its first block is Name, a component list otherwise."""
    kind = m.PlatformConf if c.is_platform_conf(r) else m.Conf
    return _BY_TYPE[kind].parse(r)


SEN_TYPES: dict[str, type] = {"rangescanner": m.RangeScan, "ins": m.Ins,
                              "odometry": m.Odometry, "contact": m.ContactReport,
                              "griptruth": m.GripTruth}
"""SEN lines with their own message type, by ``Type`` (lower case); any other is a :class:`Sen`."""


def _parse_sen(r: BlockReader) -> m.Message:
    """A SEN line's message type follows its Type block."""
    b = r.find("Type")
    kind = SEN_TYPES.get(b.value.lower(), m.Sen) if b is not None else m.Sen
    return _BY_TYPE[kind].parse(r)


_BY_HEAD: dict[str, Parse] = {"NFO": _parse_nfo, "CONF": _parse_conf, "SEN": _parse_sen}
for _spec in SPECS:
    _BY_HEAD.setdefault(_spec.head, _spec.parse)


def parse_line(text: str) -> m.Message:
    """Parse one protocol line (with or without its terminator) into a message.

    Raises:
        ProtocolError: the line breaks the grammar or a value has the wrong form; the error
            quotes the line and the column.
    """
    if cc.is_wc_status(text):  # not block grammar (an unclosed {Location)
        return cc.parse_wc_status(text)
    head, raw = split_line(text)
    parse = _BY_HEAD.get(head.upper())
    if parse is None:
        return m.Unknown(head, tuple((b.key, b.value) for b in raw))
    return parse(BlockReader(text, head, raw))


def format_message(msg: m.Message, style: NumberStyle = FULL) -> str:
    """The wire text of a message, terminated by CRLF, numbers printed in ``style``."""
    if isinstance(msg, m.Unknown):
        return line(msg.head, blocks(msg.blocks))
    if isinstance(msg, m.WcStatus):
        return cc.format_wc_status(msg, style)
    spec = _BY_TYPE.get(type(msg))
    if spec is None:
        raise TypeError(f"not a USARSim message: {msg!r}")
    return spec.format(msg, style)
