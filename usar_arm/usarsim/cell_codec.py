"""The text of a cell's lines (:mod:`.cell_messages`): the WorldController's GetSTA reply, which
breaks the block grammar, the contact report's repeated groups, and the EFF line's spacing.

GetSTA (``WorldController.GetSTA``) prints, per object::

    {Name n} {Size sx,sy,sz} {Location x,y,z {Memory {m} {Rotation r,p,y}

``{Location`` is never closed and Memory has an extra brace pair, so the reply is not a list of
blocks; :func:`parse_wc_status` reads it by its keys, and also takes the closed form a corrected
server might send (``{Location x,y,z} {Memory m} {Rotation r,p,y}``). :func:`format_wc_status`
prints UDK's exact form (vectors with ``FloatString``, 4 decimals truncated).
"""

from __future__ import annotations

import math
import re

from usar_arm.core.errors import ProtocolError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.blocks import CRLF, BlockReader, block, line
from usar_arm.usarsim.numbers import NumberStyle

_OBJECT = re.compile(
    r"\{Name (?P<name>[^{}]*?)\}\s*\{Size (?P<size>[^{}]*?)\}\s*"
    r"\{Location (?P<loc>[^{}]*?)\s*\}?\s*\{Memory\s*(?:\{(?P<mem>[^{}]*)\}|(?P<mem2>[^{}]*?))"
    r"\s*\}?\s*\{Rotation (?P<rot>[^{}]*?)\}", re.IGNORECASE)
GLUED = frozenset({"tooltype", "positiontolerance"})
"""Block keys UDK prints with no space before them (``{Status CLOSED}{ToolType ..}``,
``{Name n}{PositionTolerance ..}``: ``ToolChanger.uc``)."""


def is_wc_status(text: str) -> bool:
    """Whether a STA line is a GetSTA reply: the bare word, or objects (``{Name`` first)."""
    body = text.strip()
    if not body.upper().startswith("STA"):
        return False
    rest = body[3:].lstrip()
    return rest == "" or rest.lower().startswith("{name ")


def _vector(text: str, whole: str, at: int, key: str) -> m.Vector3:
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise ProtocolError(whole, at, f"expected three finite numbers x,y,z in {{{key} ...}}, "
                                       f"got '{text}'")
    return values  # type: ignore[return-value]


def parse_wc_status(text: str) -> m.WcStatus:
    """A GetSTA reply (UDK's unclosed form or the closed one).

    Raises:
        ProtocolError: text between or after the objects that is not an object, or a vector
            that is not three finite numbers.
    """
    whole = text.rstrip("\r\n")
    body_at = whole.upper().index("STA") + 3
    objects, pos = [], body_at
    for match in _OBJECT.finditer(whole, body_at):
        if whole[pos:match.start()].strip():
            raise ProtocolError(whole, pos, "expected {Name ..} {Size ..} {Location ..} "
                                            "{Memory ..} {Rotation ..} per object")
        memory = match.group("mem") if match.group("mem") is not None else match.group("mem2")
        objects.append(m.WcObjectStatus(
            match.group("name").strip(),
            _vector(match.group("size"), whole, match.start("size"), "Size"),
            _vector(match.group("loc"), whole, match.start("loc"), "Location"),
            (memory or "").strip(),
            _vector(match.group("rot"), whole, match.start("rot"), "Rotation")))
        pos = match.end()
    if whole[pos:].strip():
        raise ProtocolError(whole, pos, "expected {Name ..} {Size ..} {Location ..} "
                                        "{Memory ..} {Rotation ..} per object")
    return m.WcStatus(tuple(objects))


def format_wc_status(msg: m.WcStatus, s: NumberStyle) -> str:
    """UDK's exact GetSTA text (``{Location`` unclosed, Memory in an extra brace pair)."""
    def vec(v: m.Vector3) -> str:
        return ",".join(s.fixed_at(c, 4) for c in v)

    text = "STA" + "".join(
        f" {{Name {o.name}}} {{Size {vec(o.size)}}} {{Location {vec(o.location)} "
        f"{{Memory {{{o.memory}}} {{Rotation {vec(o.rotation)}}}" for o in msg.objects)
    return text + CRLF


def join_glued(parts: list[str], keys: list[str]) -> str:
    """Blocks joined by spaces, but none before a :data:`GLUED` key."""
    out = ""
    for text, key in zip(parts, keys, strict=True):
        if out and key.lower() not in GLUED:
            out += " "
        out += text
    return out


def parse_eff(r: BlockReader) -> m.Eff:
    """``EFF [{Time t}] {Type T} {Name n} <data blocks>``."""
    type_ = r.require("Type", "Gripper")
    name = r.require("Name", "gripper")
    time = r.find("Time")
    return m.Eff(type_.value, name.value, None if time is None else r.number(time),
                 r.extra("Time", "Type", "Name"))


def format_eff(msg: m.Message, s: NumberStyle) -> str:
    """UDK's ``GetHead() @ GetData()``, a ToolChanger's ``}{ToolType`` glued."""
    assert isinstance(msg, m.Eff)
    head = ([block("Time", s.scalar(msg.time))] if msg.time is not None else []) + [
        block("Type", msg.type), block("Name", msg.name)]
    keys = [k for k, _ in msg.extra]
    data = join_glued([block(k, v) for k, v in msg.extra], keys)
    return line("EFF", [*head, data] if data else head)


def parse_contact_report(r: BlockReader) -> m.ContactReport:
    """``SEN {Time t} {Type Contact} {Name n} {Count k} ({Pair a b} {First ..} {Last ..}
    {Depth ..} {Steps ..})*``."""
    time = r.find("Time")
    type_ = r.require("Type", "Contact")
    name = r.require("Name", "KR60")
    count = r.require("Count", "0")
    pairs, i, blocks = [], 0, r.blocks
    while i < len(blocks):
        b = blocks[i]
        if b.key.lower() != "pair":
            i += 1
            continue
        group = {g.key.lower(): g for g in blocks[i + 1:i + 5]}
        bodies = b.value.split()
        if len(bodies) != 2 or set(group) != {"first", "last", "depth", "steps"}:
            raise r.error(b, "expected {Pair a b} {First t} {Last t} {Depth d} {Steps n}")
        pairs.append(m.ContactPair(bodies[0], bodies[1], r.number(group["first"]),
                                   r.number(group["last"]), r.number(group["depth"]),
                                   r.int(group["steps"])))
        i += 5
    if r.int(count) != len(pairs):
        raise r.error(count, f"Count says {count.value} but {len(pairs)} pair(s) follow")
    return m.ContactReport(name.value, tuple(pairs), None if time is None else r.number(time),
                           type_.value)


def format_contact_report(msg: m.Message, s: NumberStyle) -> str:
    """The text of a :class:`~.cell_messages.ContactReport` (times and depths as scalars)."""
    assert isinstance(msg, m.ContactReport)
    parts = ([block("Time", s.scalar(msg.time))] if msg.time is not None else []) + [
        block("Type", msg.type), block("Name", msg.name), block("Count", str(len(msg.pairs)))]
    for p in msg.pairs:
        parts += [block("Pair", f"{p.a} {p.b}"), block("First", s.scalar(p.first)),
                  block("Last", s.scalar(p.last)), block("Depth", s.scalar(p.depth)),
                  block("Steps", str(p.steps))]
    return line("SEN", parts)
