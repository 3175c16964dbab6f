"""The block grammar of USARSim lines: ``COMMAND {Key value} {Key value} ...`` + CRLF.

:func:`split_line` checks the grammar and cuts a line into its command word and blocks;
:class:`BlockReader` reads typed values from them, raising
:class:`~usar_arm.core.errors.ProtocolError` with the column of the offending block; :func:`block`
and :func:`line` print them. Message-level meaning lives in :mod:`.codec` and :mod:`.compound`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from usar_arm.core.errors import ProtocolError
from usar_arm.usarsim import messages as m

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


class BlockReader:
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


def block(key: str, value: str) -> str:
    """``{key value}`` (``{key}`` for an empty value)."""
    return f"{{{key} {value}}}" if value != "" else f"{{{key}}}"


def blocks(pairs: tuple[m.Block, ...] | list[m.Block]) -> list[str]:
    """Each ``(key, value)`` pair printed as a block."""
    return [block(k, v) for k, v in pairs]


def line(head: str, parts: list[str], glue: str = " ") -> str:
    """A whole line: the command word, the printed blocks, CRLF."""
    return (head + (" " + glue.join(parts) if parts else "")) + CRLF
