"""The USARSim messages whose wire form is more than a list of keyed fields: start poses,
ACT and ASTA (Link/Value pairs), CONF and GEO (items with per-link groups). Each has its parse and
its format side by side here; :mod:`.codec` registers them next to the field-table messages.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

from usar_arm.core.errors import ProtocolError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.blocks import CRLF, BlockReader, RawBlock, block, blocks, line
from usar_arm.usarsim.cell_codec import join_glued
from usar_arm.usarsim.numbers import NumberStyle

# ------------------------------------------------------------------------- start poses

def parse_start_poses(r: BlockReader) -> m.StartPoses:
    """``NFO {StartPoses N} {Name1 x,y,z r,p,y Name2 ...}``."""
    count_block = r.require("StartPoses", "2")
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



def format_start_poses(msg: m.Message, s: NumberStyle) -> str:
    """The wire text of :class:`~.messages.StartPoses`."""
    assert isinstance(msg, m.StartPoses)
    parts = [block("StartPoses", str(len(msg.poses)))]
    if msg.poses:
        text = " ".join(f"{p.name} {s.raw_vector(p.location)} {s.raw_vector(p.rotation)}"
                        for p in msg.poses)
        parts.append("{" + text + "}")
    return line("NFO", parts)


# ------------------------------------------------------------------------- ACT and ASTA

def _pairs(r: BlockReader, case_sensitive: bool) -> tuple[list[tuple[int, float]], list[RawBlock]]:
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


def parse_act(r: BlockReader) -> m.Act:
    """``ACT {Name a} {Link i} {Value v} ... [{Gripper g}] [{Sequence s}]``."""
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


def parse_asta(r: BlockReader) -> m.Asta:
    """``ASTA {Time t} {Name a} {Link i} {Value v} ...``."""
    pairs, rest = _pairs(r, case_sensitive=False)
    time = _take_first(rest, "Time")
    name = _take_first(rest, "Name")
    if time is None or name is None:
        raise ProtocolError(r.line, len(r.line), "ASTA needs {Time t} and {Name arm}")
    return m.Asta(r.number(time), name.value, tuple(pairs), tuple((b.key, b.value) for b in rest))


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

    return blocks(sorted(extra, key=rank))


def format_act(msg: m.Message, s: NumberStyle) -> str:
    """The wire text of :class:`~.messages.Act`."""
    assert isinstance(msg, m.Act)
    parts = [block("Name", msg.name)]
    for link, value in msg.targets:
        parts += [block("Link", str(link)), block("Value", s.scalar(value))]
    if msg.gripper is not None:
        parts.append(block("Gripper", str(msg.gripper)))
    if msg.sequence is not None:
        parts.append(block("Sequence", str(msg.sequence)))
    return line("ACT", parts + _unpaired(msg.extra, str.__eq__))


def format_asta(msg: m.Message, s: NumberStyle) -> str:
    """The wire text of :class:`~.messages.Asta`."""
    assert isinstance(msg, m.Asta)
    parts = [block("Time", s.scalar(msg.time)), block("Name", msg.name)]
    for link, value in msg.values:
        parts += [block("Link", str(link)), block("Value", s.scalar(value))]
    return line("ASTA", parts + _unpaired(msg.extra, _same_key))


# ------------------------------------------------------------------------- CONF and GEO

def is_platform_conf(r: BlockReader) -> bool:
    """A CONF whose first block is its Name is the platform's (UDK prints Name before Type)."""
    return bool(r.blocks) and r.blocks[0].key.lower() == "name"


def parse_platform_conf(r: BlockReader) -> m.PlatformConf:
    """``CONF {Name KR60} {Type StaticPlatform} ...``."""
    return m.PlatformConf(
        name=r.blocks[0].value,
        type=r.require("Type", "StaticPlatform").value,
        fields=r.extra("Name", "Type"),
    )


def format_platform_conf(msg: m.Message, s: NumberStyle) -> str:
    """The wire text of :class:`~.messages.PlatformConf` (UDK leaves a trailing space)."""
    assert isinstance(msg, m.PlatformConf)
    parts = [block("Name", msg.name), block("Type", msg.type), *blocks(msg.fields)]
    return line("CONF", parts).replace(CRLF, " " + CRLF)


def format_conf(msg: m.Message, s: NumberStyle) -> str:
    """The wire text of :class:`~.messages.Conf`."""
    assert isinstance(msg, m.Conf)
    return line("CONF", [block("Type", msg.type)] + [_conf_item(i, s) for i in msg.items])


def _keyed(r: BlockReader, skip: RawBlock) -> Iterator[tuple[str, RawBlock]]:
    """The line's blocks but ``skip`` (its ``{Type ..}``), each with its lower-case key."""
    for b in r.blocks:
        if b is not skip:
            yield b.key.lower(), b


def parse_conf(r: BlockReader) -> m.Conf:
    """``CONF {Type T} {Name a} ... {Link i} ...``: per-component fields and link groups."""
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
    for k, b in _keyed(r, type_block):
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


def parse_geo(r: BlockReader) -> m.Geo:
    """``GEO {Type T} {Name a} {Location ..} ... {Link i} {Parent p} ... {Tip ..}``."""
    type_block = r.require("Type", "Actuator")
    items: list[m.GeoItem] = []
    item: dict[str, Any] | None = None
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
            items.append(m.GeoItem(links=tuple(links), extra=tuple(item_extra), **item))
        item, links, item_extra = None, [], []

    for k, b in _keyed(r, type_block):
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


def format_geo(msg: m.Message, s: NumberStyle) -> str:
    """The wire text of :class:`~.messages.Geo`."""
    assert isinstance(msg, m.Geo)
    raw = msg.type.lower() in RAW_GEO_TYPES
    return line("GEO", [block("Type", msg.type)] + [_geo_item(i, s, raw) for i in msg.items])


RAW_GEO_TYPES = frozenset({"gripper", "toolchanger", "effector"})
"""GEO types whose Location and Orientation UDK prints as raw vectors (2 decimals,
``Effector.GetGeoData``), not with FloatString as sensors' and actuators' are."""


def _conf_item(item: m.ConfItem, s: NumberStyle) -> str:
    head = join_glued([block("Name", item.name), *blocks(item.fields)],  # }{PositionTolerance
                      ["Name", *(k for k, _ in item.fields)])
    parts = [head]
    for ln in item.links:
        parts += [block("Link", str(ln.link)), block("JointType", ln.joint_type)]
        for key, value in (("MaxSpeed", ln.max_speed), ("MaxTorque", ln.max_torque),
                           ("MinValue", ln.min_value), ("MaxValue", ln.max_value)):
            if value is not None:
                parts.append(block(key, s.scalar(value)))
        parts += blocks(ln.extra)
    return " ".join(parts)


def _geo_item(item: m.GeoItem, s: NumberStyle, raw: bool = False) -> str:
    vector = s.raw_vector if raw else s.fixed_vector
    text = block("Name", item.name)
    if item.location is not None:
        text += " " + block("Location", vector(item.location))
    if item.orientation is not None:
        text += " " + block("Orientation", vector(item.orientation))
    if item.mount is not None:
        text += block("Mount", item.mount)  # UDK: no space before {Mount
    if item.mount_link is not None:
        text += block("MountLink", str(item.mount_link))
    # Extra Tip blocks go after the item's Tip: printed first, one would become the Tip.
    late = [(k, v) for k, v in item.extra if k.lower() == "tip"]
    for key, value in item.extra:
        if key.lower() != "tip":
            text += " " + block(key, value)
    for ln in item.links:
        text += " " + " ".join([
            block("Link", str(ln.link)), block("Parent", str(ln.parent)),
            block("Location", s.fixed_vector(ln.location)),
            block("Orientation", s.raw_vector(ln.orientation)), *blocks(ln.extra)])
    if item.tip is not None:
        text += block("Tip", s.raw_vector(item.tip))  # UDK: no space before {Tip
    for key, value in late:
        text += " " + block(key, value)
    return text
