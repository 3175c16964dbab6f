"""Pure text <-> message conversion for the USARSim UDK protocol.

Grammar (usarsim-protocol.md section 2): ``COMMAND {Key value} {Key value} ...`` + CRLF. The
command word is the text before the first ``{`` and is matched case-insensitively. Each block is
split at its first whitespace into key and value; the value may contain spaces and commas and is
trimmed. Blocks may touch (``}{Mount``). Keys are matched case-insensitively, except ``Link`` and
``Value`` in ACT, which UDK compares case-sensitively. Vectors are ``x,y,z``. Numbers must be
finite: ``nan`` and ``inf``, which Python's ``float`` accepts, are refused (no USARSim server
prints them, and they would poison joint values and limits downstream).

:func:`parse_line` raises :class:`~usar_arm.errors.ProtocolError` quoting the line and the column
of the problem. :func:`format_message` prints numbers in a :class:`NumberStyle` (default: full
float64 precision, so ``parse_line(format_message(m)) == m``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from usar_arm.errors import ProtocolError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import FULL, NumberStyle

CRLF = "\r\n"
MAX_LINE_BYTES = 64 * 1024
"""Longest line either side accepts (64 KiB); longer lines are refused and skipped."""


@dataclass(frozen=True)
class RawBlock:
    """A ``{key value}`` block and the column of its ``{`` in the line."""

    key: str
    value: str
    pos: int


def split_line(line: str) -> tuple[str, list[RawBlock]]:
    """Split a line into its command word and blocks, checking the block grammar."""
    text = line.rstrip("\r\n")
    first = text.find("{")
    head_text = text if first < 0 else text[:first]
    if "}" in head_text:
        raise ProtocolError(text, head_text.index("}"), "'}' without a matching '{'")
    head = head_text.strip()
    if not head:
        raise ProtocolError(text, 0, "expected a command word (such as ASTA or GETCONF) first")
    if len(head.split()) != 1:
        pos = len(head_text) - len(head_text.lstrip()) + len(head.split()[0])
        raise ProtocolError(text, pos, "the command word must be a single word")
    blocks: list[RawBlock] = []
    pos = first
    while 0 <= pos < len(text):
        ch = text[pos]
        if ch.isspace():
            pos += 1
        elif ch == "{":
            end = text.find("}", pos + 1)
            nested = text.find("{", pos + 1)
            if end < 0:
                raise ProtocolError(text, pos, "'{' is never closed: expected '}'")
            if 0 <= nested < end:
                raise ProtocolError(text, nested, "'{' inside a block (USARSim blocks do not nest)")
            inner = text[pos + 1 : end].strip()
            if not inner:
                raise ProtocolError(text, pos, "empty block: expected {Key value}")
            parts = inner.split(None, 1)
            blocks.append(RawBlock(parts[0], parts[1].strip() if len(parts) > 1 else "", pos))
            pos = end + 1
        elif ch == "}":
            raise ProtocolError(text, pos, "'}' without a matching '{'")
        else:
            raise ProtocolError(text, pos, "text outside a block: expected '{' or the end of line")
    return head, blocks


class _Reader:
    """Typed access to the blocks of one line, raising ProtocolError with the block's column."""

    def __init__(self, line: str, head: str, blocks: list[RawBlock]):
        self.line = line.rstrip("\r\n")
        self.head = head
        self.blocks = blocks

    def error(self, block: RawBlock | None, reason: str) -> ProtocolError:
        return ProtocolError(self.line, block.pos if block else 0, reason)

    def find(self, key: str) -> RawBlock | None:
        for b in self.blocks:
            if b.key.lower() == key.lower():
                return b
        return None

    def require(self, key: str, example: str) -> RawBlock:
        b = self.find(key)
        if b is None:
            raise ProtocolError(self.line, len(self.line), f"{self.head} needs {{{key} {example}}}")
        return b

    def number(self, b: RawBlock) -> float:
        try:
            value = float(b.value)
        except ValueError:
            raise self.error(b, f"expected a number in {{{b.key} ...}}, got '{b.value}'") from None
        if not math.isfinite(value):
            raise self.error(b, f"expected a finite number in {{{b.key} ...}}, got '{b.value}'")
        return value

    def int(self, b: RawBlock) -> int:
        try:
            return int(b.value)
        except ValueError:
            raise self.error(
                b, f"expected an integer in {{{b.key} ...}}, got '{b.value}'") from None

    def vector(self, b: RawBlock, text: str | None = None) -> m.Vector3:
        raw = b.value if text is None else text
        parts = raw.split(",")
        if len(parts) != 3:
            raise self.error(b, f"expected a vector x,y,z in {{{b.key} ...}}, got '{raw}'")
        try:
            x, y, z = (float(p) for p in parts)
        except ValueError:
            raise self.error(b, f"expected three numbers x,y,z in {{{b.key} ...}}, got '{raw}'") \
                from None
        if not all(math.isfinite(v) for v in (x, y, z)):
            raise self.error(b, f"expected three finite numbers x,y,z in {{{b.key} ...}}, "
                                f"got '{raw}'")
        return (x, y, z)

    def opt_float(self, key: str) -> float | None:
        b = self.find(key)
        return None if b is None else self.number(b)

    def opt_str(self, key: str) -> str | None:
        b = self.find(key)
        return None if b is None else b.value

    def opt_vector(self, key: str) -> m.Vector3 | None:
        b = self.find(key)
        return None if b is None else self.vector(b)

    def extra(self, *known: str) -> tuple[m.Block, ...]:
        lowered = {k.lower() for k in known}
        seen: set[str] = set()
        out = []
        for b in self.blocks:
            k = b.key.lower()
            if k in lowered and k not in seen:
                seen.add(k)
                continue
            out.append((b.key, b.value))
        return tuple(out)


# --------------------------------------------------------------------------------- parsing


def _parse_nfo(r: _Reader) -> m.GameInfo | m.StartPoses:
    count_block = r.find("StartPoses")
    if count_block is None:
        return m.GameInfo(
            gametype=r.opt_str("Gametype") or "",
            level=r.opt_str("Level") or "",
            time_limit=r.opt_float("TimeLimit"),
            extra=r.extra("Gametype", "Level", "TimeLimit"),
        )
    count = r.int(count_block)
    index = r.blocks.index(count_block)
    tokens: list[str] = []
    token_block: RawBlock | None = None
    if index + 1 < len(r.blocks):
        token_block = r.blocks[index + 1]
        tokens = [token_block.key, *token_block.value.split()]
    if len(tokens) % 3 != 0 or len(tokens) // 3 != count:
        raise r.error(token_block or count_block,
                      f"StartPoses says {count} pose(s) but the pose block holds "
                      f"{len(tokens) / 3:g}: expected 'Name x,y,z r,p,y' per pose")
    poses = []
    for i in range(0, len(tokens), 3):
        assert token_block is not None
        poses.append(m.StartPose(tokens[i], r.vector(token_block, tokens[i + 1]),
                                 r.vector(token_block, tokens[i + 2])))
    return m.StartPoses(tuple(poses))


def _parse_init(r: _Reader) -> m.Init:
    return m.Init(
        class_name=r.require("ClassName", "USARBot.KR60").value,
        name=r.opt_str("Name"),
        start=r.opt_str("Start"),
        location=r.opt_vector("Location"),
        rotation=r.opt_vector("Rotation"),
        extra=r.extra("ClassName", "Name", "Start", "Location", "Rotation"),
    )


def _pairs(r: _Reader, case_sensitive: bool) -> tuple[list[tuple[int, float]], list[RawBlock]]:
    """Scan Link/Value pairs: a Link block immediately followed by a Value block.

    Returns the pairs and the blocks that are not part of a pair, in order.
    """
    def is_key(b: RawBlock, key: str) -> bool:
        return b.key == key if case_sensitive else b.key.lower() == key.lower()

    pairs: list[tuple[int, float]] = []
    rest: list[RawBlock] = []
    i = 0
    blocks = r.blocks
    while i < len(blocks):
        b = blocks[i]
        if is_key(b, "Link") and i + 1 < len(blocks) and is_key(blocks[i + 1], "Value"):
            pairs.append((r.int(b), r.number(blocks[i + 1])))
            i += 2
        else:
            rest.append(b)
            i += 1
    return pairs, rest


def _take_first(blocks: list[RawBlock], key: str, match: Callable[[str, str], bool] | None = None
                ) -> RawBlock | None:
    """Remove and return the first block whose key matches (case-insensitive by default)."""
    same = match or (lambda a, b: a.lower() == b.lower())
    for i, b in enumerate(blocks):
        if same(b.key, key):
            return blocks.pop(i)
    return None


def _parse_act(r: _Reader) -> m.Act:
    pairs, rest = _pairs(r, case_sensitive=True)
    name = _take_first(rest, "Name")
    if name is None:
        raise ProtocolError(r.line, len(r.line), "ACT needs {Name KR60Arm}")
    exact = str.__eq__
    gripper = _take_first(rest, "Gripper", exact)
    sequence = _take_first(rest, "Sequence", exact) or _take_first(rest, "Seq", exact)
    return m.Act(name.value, tuple(pairs),
                 None if gripper is None else r.int(gripper),
                 None if sequence is None else r.int(sequence),
                 tuple((b.key, b.value) for b in rest))


def _parse_bool(r: _Reader, key: str) -> bool | None:
    b = r.find(key)
    if b is None:
        return None
    if b.value.lower() in ("true", "1"):
        return True
    if b.value.lower() in ("false", "0"):
        return False
    raise r.error(b, f"expected true or false in {{{key} ...}}, got '{b.value}'")


def _parse_conf(r: _Reader) -> m.Conf | m.PlatformConf:
    if r.blocks and r.blocks[0].key.lower() == "name":
        return m.PlatformConf(
            name=r.blocks[0].value,
            type=r.require("Type", "StaticPlatform").value,
            fields=r.extra("Name", "Type"),
        )
    type_block = r.require("Type", "Actuator")
    items: list[m.ConfItem] = []
    name: str | None = None
    fields: list[m.Block] = []
    links: list[m.LinkConf] = []
    link: dict[str, RawBlock] | None = None
    link_extra: list[m.Block] = []

    def close_link() -> None:
        nonlocal link, link_extra
        if link is not None:
            lb = link["link"]
            jt = link.get("jointtype")
            links.append(m.LinkConf(
                link=r.int(lb), joint_type=jt.value if jt else "Unknown",
                max_torque=r.number(link["maxtorque"]) if "maxtorque" in link else None,
                min_value=r.number(link["minvalue"]) if "minvalue" in link else None,
                max_value=r.number(link["maxvalue"]) if "maxvalue" in link else None,
                max_speed=r.number(link["maxspeed"]) if "maxspeed" in link else None,
                extra=tuple(link_extra)))
        link, link_extra = None, []

    def close_item() -> None:
        nonlocal name, fields, links
        close_link()
        if name is not None:
            items.append(m.ConfItem(name, tuple(fields), tuple(links)))
        name, fields, links = None, [], []

    link_keys = ("jointtype", "maxtorque", "minvalue", "maxvalue", "maxspeed")
    for b in r.blocks:
        k = b.key.lower()
        if b is type_block:
            continue
        if k == "name":
            close_item()
            name = b.value
        elif name is None:
            raise r.error(b, "expected {Name ..} before the fields of a CONF item")
        elif k == "link":
            close_link()
            link = {"link": b}
        elif link is not None and k in link_keys and k not in link:
            link[k] = b
        elif link is not None:
            link_extra.append((b.key, b.value))
        else:
            fields.append((b.key, b.value))
    close_item()
    return m.Conf(type_block.value, tuple(items))


def _parse_geo(r: _Reader) -> m.Geo:
    type_block = r.require("Type", "Actuator")
    items: list[m.GeoItem] = []
    item: dict[str, object] | None = None
    links: list[m.LinkGeo] = []
    link: dict[str, RawBlock] | None = None
    link_extra: list[m.Block] = []
    item_extra: list[m.Block] = []

    def close_link() -> None:
        nonlocal link, link_extra
        if link is not None:
            lb = link["link"]
            for need in ("parent", "location", "orientation"):
                if need not in link:
                    raise r.error(lb, f"GEO link {lb.value} has no {{{need.title()} ..}}")
            links.append(m.LinkGeo(r.int(lb), r.int(link["parent"]),
                                   r.vector(link["location"]), r.vector(link["orientation"]),
                                   tuple(link_extra)))
        link, link_extra = None, []

    def close_item() -> None:
        nonlocal item, links, item_extra
        close_link()
        if item is not None:
            items.append(m.GeoItem(links=tuple(links), extra=tuple(item_extra),
                                   **item))  # type: ignore[arg-type]
        item, links, item_extra = None, [], []

    for b in r.blocks:
        k = b.key.lower()
        if b is type_block:
            continue
        if k == "name":
            close_item()
            item = {"name": b.value}
        elif item is None:
            raise r.error(b, "expected {Name ..} before the fields of a GEO item")
        elif k == "link":
            close_link()
            link = {"link": b}
        elif k == "tip" and "tip" not in item:
            close_link()
            item["tip"] = r.vector(b)
        elif k == "tip":  # a second Tip is kept with the item, never with a link
            item_extra.append((b.key, b.value))
        elif link is not None and k in ("parent", "parentlink") and "parent" not in link:
            link["parent"] = b
        elif link is not None and k in ("location", "orientation") and k not in link:
            link[k] = b
        elif link is not None:
            link_extra.append((b.key, b.value))
        elif k in ("location", "orientation") and k not in item:
            item[k] = r.vector(b)
        elif k == "mount" and "mount" not in item:
            item["mount"] = b.value
        elif k == "mountlink" and "mount_link" not in item:
            item["mount_link"] = r.int(b)
        else:
            item_extra.append((b.key, b.value))
    close_item()
    return m.Geo(type_block.value, tuple(items))


def _parse_asta(r: _Reader) -> m.Asta:
    pairs, rest = _pairs(r, case_sensitive=False)
    time = _take_first(rest, "Time")
    name = _take_first(rest, "Name")
    if time is None or name is None:
        raise ProtocolError(r.line, len(r.line), "ASTA needs {Time t} and {Name arm}")
    return m.Asta(r.number(time), name.value, tuple(pairs), tuple((b.key, b.value) for b in rest))


def _battery(r: _Reader, b: RawBlock) -> int:
    """The battery life: an integer as UDK prints it, or a number truncated toward zero."""
    try:
        return int(b.value)
    except ValueError:
        return int(r.number(b))


def _parse_sta(r: _Reader) -> m.Sta:
    battery = r.find("Battery")
    return m.Sta(
        time=r.number(r.require("Time", "12.5")),
        battery=None if battery is None else _battery(r, battery),
        type=r.opt_str("Type"),
        extra=r.extra("Time", "Battery", "Type"),
    )


def _parse_sen(r: _Reader) -> m.Sen:
    return m.Sen(
        type=r.require("Type", "GroundTruth").value,
        name=r.require("Name", "GroundTruth").value,
        time=r.opt_float("Time"),
        location=r.opt_vector("Location"),
        orientation=r.opt_vector("Orientation"),
        extra=r.extra("Type", "Name", "Time", "Location", "Orientation"),
    )


def _parse_eff(r: _Reader) -> m.Eff:
    return m.Eff(type=r.require("Type", "Gripper").value, name=r.require("Name", "gripper").value,
                 time=r.opt_float("Time"), extra=r.extra("Type", "Name", "Time"))


_PARSERS: dict[str, Callable[[_Reader], m.Message]] = {
    "NFO": _parse_nfo,
    "GETSTARTPOSES": lambda r: m.GetStartPoses(),
    "INIT": _parse_init,
    "GETCONF": lambda r: m.GetConf(r.require("Type", "Actuator").value, r.opt_str("Name")),
    "GETGEO": lambda r: m.GetGeo(r.require("Type", "Actuator").value, r.opt_str("Name")),
    "ACT": _parse_act,
    "SET": lambda r: m.Set(r.require("Type", "Gripper").value, r.require("Name", "gripper").value,
                           r.require("Opcode", "OPEN").value, r.opt_str("Params")),
    "DRIVE": lambda r: m.Drive(r.opt_float("Left"), r.opt_float("Right"),
                               _parse_bool(r, "Normalized"), _parse_bool(r, "Light"),
                               r.extra("Left", "Right", "Normalized", "Light")),
    "CONF": _parse_conf,
    "GEO": _parse_geo,
    "ASTA": _parse_asta,
    "STA": _parse_sta,
    "SEN": _parse_sen,
    "EFF": _parse_eff,
}


def parse_line(line: str) -> m.Message:
    """Parse one protocol line (with or without its terminator) into a message.

    Raises:
        ProtocolError: the line breaks the grammar or a value has the wrong form; the error
            quotes the line and the column.
    """
    head, blocks = split_line(line)
    parser = _PARSERS.get(head.upper())
    if parser is None:
        return m.Unknown(head, tuple((b.key, b.value) for b in blocks))
    return parser(_Reader(line, head, blocks))


# ------------------------------------------------------------------------------ formatting


def _block(key: str, value: str) -> str:
    return f"{{{key} {value}}}" if value != "" else f"{{{key}}}"


def _blocks(pairs: list[tuple[str, str]] | tuple[m.Block, ...]) -> list[str]:
    return [_block(k, v) for k, v in pairs]


def _same_key(a: str, b: str) -> bool:
    return a.lower() == b.lower()


def _unpaired(extra: tuple[m.Block, ...], same: Callable[[str, str], bool]) -> list[str]:
    """The extra blocks of an ACT or ASTA line, printed so that they cannot pair up.

    A ``{Link}`` or ``{Value}`` block lands in ``extra`` when it was not part of a Link/Value
    pair on input; printed in order, a stray Link followed by a stray Value would become a pair
    (with a Link that may not even be an integer). Value blocks go first and Link blocks last,
    so no Link is ever followed by a Value; the other blocks keep their order.
    """
    def rank(block: m.Block) -> int:
        return 0 if same(block[0], "Value") else 2 if same(block[0], "Link") else 1

    return _blocks(sorted(extra, key=rank))


def _line(head: str, parts: list[str], glue: str = " ") -> str:
    return (head + (" " + glue.join(parts) if parts else "")) + CRLF


def _opt(parts: list[str], key: str, value: object, fmt: Callable[[object], str] = str) -> None:
    if value is not None:
        parts.append(_block(key, fmt(value)))


def format_message(msg: m.Message, style: NumberStyle = FULL) -> str:
    """The wire text of a message, terminated by CRLF, numbers printed in ``style``."""
    s = style
    sc = s.scalar
    if isinstance(msg, m.GameInfo):
        parts = [_block("Gametype", msg.gametype), _block("Level", msg.level)]
        _opt(parts, "TimeLimit", msg.time_limit, lambda v: sc(v))  # type: ignore[arg-type]
        return _line("NFO", parts + _blocks(msg.extra))
    if isinstance(msg, m.StartPoses):
        parts = [_block("StartPoses", str(len(msg.poses)))]
        if msg.poses:
            text = " ".join(f"{p.name} {s.raw_vector(p.location)} {s.raw_vector(p.rotation)}"
                            for p in msg.poses)
            parts.append("{" + text + "}")
        return _line("NFO", parts)
    if isinstance(msg, m.GetStartPoses):
        return "GETSTARTPOSES" + CRLF
    if isinstance(msg, m.Init):
        parts = [_block("ClassName", msg.class_name)]
        _opt(parts, "Name", msg.name)
        _opt(parts, "Start", msg.start)
        _opt(parts, "Location", msg.location, s.raw_vector)  # type: ignore[arg-type]
        _opt(parts, "Rotation", msg.rotation, s.raw_vector)  # type: ignore[arg-type]
        return _line("INIT", parts + _blocks(msg.extra))
    if isinstance(msg, (m.GetConf, m.GetGeo)):
        parts = [_block("Type", msg.type)]
        _opt(parts, "Name", msg.name)
        return _line("GETCONF" if isinstance(msg, m.GetConf) else "GETGEO", parts)
    if isinstance(msg, m.Act):
        parts = [_block("Name", msg.name)]
        for link, value in msg.targets:
            parts += [_block("Link", str(link)), _block("Value", sc(value))]
        _opt(parts, "Gripper", msg.gripper)
        _opt(parts, "Sequence", msg.sequence)
        return _line("ACT", parts + _unpaired(msg.extra, str.__eq__))
    if isinstance(msg, m.Set):
        parts = [_block("Type", msg.type), _block("Name", msg.name), _block("Opcode", msg.opcode)]
        _opt(parts, "Params", msg.params)
        return _line("SET", parts)
    if isinstance(msg, m.Drive):
        parts = []
        _opt(parts, "Left", msg.left, lambda v: sc(v))  # type: ignore[arg-type]
        _opt(parts, "Right", msg.right, lambda v: sc(v))  # type: ignore[arg-type]
        _opt(parts, "Normalized", msg.normalized, lambda v: str(v).lower())
        _opt(parts, "Light", msg.light, lambda v: str(v).lower())
        return _line("DRIVE", parts + _blocks(msg.extra))
    if isinstance(msg, m.PlatformConf):
        parts = [_block("Name", msg.name), _block("Type", msg.type), *_blocks(msg.fields)]
        # UDK leaves a trailing space after the platform CONF.
        return _line("CONF", parts).replace(CRLF, " " + CRLF)
    if isinstance(msg, m.Conf):
        return _line("CONF", [_block("Type", msg.type)] + [_conf_item(i, s) for i in msg.items])
    if isinstance(msg, m.Geo):
        return _line("GEO", [_block("Type", msg.type)] + [_geo_item(i, s) for i in msg.items])
    if isinstance(msg, m.Asta):
        parts = [_block("Time", sc(msg.time)), _block("Name", msg.name)]
        for link, value in msg.values:
            parts += [_block("Link", str(link)), _block("Value", sc(value))]
        return _line("ASTA", parts + _unpaired(msg.extra, _same_key))
    if isinstance(msg, m.Sta):
        parts = [_block("Time", sc(msg.time))]
        _opt(parts, "Battery", msg.battery)
        _opt(parts, "Type", msg.type)
        return _line("STA", parts + _blocks(msg.extra))
    if isinstance(msg, m.Sen):
        parts = []
        _opt(parts, "Time", msg.time, lambda v: sc(v))  # type: ignore[arg-type]
        parts += [_block("Type", msg.type), _block("Name", msg.name)]
        _opt(parts, "Location", msg.location, s.fixed_vector)  # type: ignore[arg-type]
        _opt(parts, "Orientation", msg.orientation, s.fixed_vector)  # type: ignore[arg-type]
        return _line("SEN", parts + _blocks(msg.extra))
    if isinstance(msg, m.Eff):
        parts = []
        _opt(parts, "Time", msg.time, lambda v: sc(v))  # type: ignore[arg-type]
        parts += [_block("Type", msg.type), _block("Name", msg.name)]
        return _line("EFF", parts + _blocks(msg.extra))
    if isinstance(msg, m.Unknown):
        return _line(msg.head, _blocks(msg.blocks))
    raise TypeError(f"not a USARSim message: {msg!r}")


def _conf_item(item: m.ConfItem, s: NumberStyle) -> str:
    parts = [_block("Name", item.name), *_blocks(item.fields)]
    for ln in item.links:
        parts += [_block("Link", str(ln.link)), _block("JointType", ln.joint_type)]
        _opt(parts, "MaxSpeed", ln.max_speed, lambda v: s.scalar(v))  # type: ignore[arg-type]
        _opt(parts, "MaxTorque", ln.max_torque, lambda v: s.scalar(v))  # type: ignore[arg-type]
        _opt(parts, "MinValue", ln.min_value, lambda v: s.scalar(v))  # type: ignore[arg-type]
        _opt(parts, "MaxValue", ln.max_value, lambda v: s.scalar(v))  # type: ignore[arg-type]
        parts += _blocks(ln.extra)
    return " ".join(parts)


def _geo_item(item: m.GeoItem, s: NumberStyle) -> str:
    text = _block("Name", item.name)
    if item.location is not None:
        text += " " + _block("Location", s.fixed_vector(item.location))
    if item.orientation is not None:
        text += " " + _block("Orientation", s.fixed_vector(item.orientation))
    if item.mount is not None:
        text += _block("Mount", item.mount)  # UDK: no space before {Mount
    if item.mount_link is not None:
        text += _block("MountLink", str(item.mount_link))
    # Extra Tip blocks go after the item's Tip: printed first, one would become the Tip.
    late = [(k, v) for k, v in item.extra if k.lower() == "tip"]
    for key, value in item.extra:
        if key.lower() != "tip":
            text += " " + _block(key, value)
    for ln in item.links:
        text += " " + " ".join([
            _block("Link", str(ln.link)), _block("Parent", str(ln.parent)),
            _block("Location", s.fixed_vector(ln.location)),
            _block("Orientation", s.raw_vector(ln.orientation)), *_blocks(ln.extra)])
    if item.tip is not None:
        text += _block("Tip", s.raw_vector(item.tip))  # UDK: no space before {Tip
    for key, value in late:
        text += " " + _block(key, value)
    return text
