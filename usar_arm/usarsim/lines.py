"""Framing of the USARSim byte stream into text lines: CR, LF or CRLF ends a line, a line is
printable ASCII text, and an overlong line is reported once and skipped so memory stays bounded.
"""

from __future__ import annotations

from dataclasses import dataclass

from usar_arm.core.errors import ProtocolError
from usar_arm.usarsim.codec import MAX_LINE_BYTES


@dataclass(frozen=True)
class BadLine:
    """A line from the server that is not USARSim: its command word ('' when it has none, or
    the line was too long to read one) and what was wrong."""

    head: str
    error: ProtocolError


def _printable(text: str) -> str:
    """``text`` with control characters shown as '?' (columns unchanged)."""
    return "".join("?" if (ch < " " and ch != "\t") or ch == "\x7f" else ch for ch in text)


def decode_line(raw: bytes) -> str:
    """The text of one raw line (no terminator).

    Raises:
        ProtocolError: the bytes are not UTF-8, or hold control characters (USARSim lines are
            printable ASCII text).
    """
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        shown = _printable(raw.decode("utf-8", "replace"))
        raise ProtocolError(shown, max(0, shown.find("\ufffd")),
                            f"byte 0x{raw[exc.start]:02x} at offset {exc.start} is not UTF-8 "
                            "text: expected a USARSim line (printable ASCII)") from None
    bad = next((i for i, ch in enumerate(text) if (ch < " " and ch != "\t") or ch == "\x7f"),
               None)
    if bad is not None:
        raise ProtocolError(_printable(text), bad,
                            f"control character 0x{ord(text[bad]):02x}: expected a USARSim line "
                            "(printable ASCII)")
    return text


class LineSplitter:
    """Splits received bytes into lines at CR, LF or CRLF.

    A line longer than ``limit`` bytes is reported once (as a :class:`BadLine`) as soon as the
    limit is passed, and its remaining bytes are dropped up to its line end: memory stays
    bounded by ``limit`` whatever arrives.
    """

    def __init__(self, limit: int = MAX_LINE_BYTES):
        self.limit = limit
        self.buffer = bytearray()
        self.skipping = False

    @property
    def partial(self) -> int:
        """Bytes of an unfinished line held (0 while skipping an overlong one)."""
        return len(self.buffer)

    def feed(self, chunk: bytes) -> list[bytes | BadLine]:
        """The complete lines (without terminators, blank ones dropped) in ``chunk``, and a
        BadLine for a line that has grown past the limit."""
        out: list[bytes | BadLine] = []
        start = 0
        while start < len(chunk):
            cuts = [i for i in (chunk.find(b"\n", start), chunk.find(b"\r", start)) if i >= 0]
            end = min(cuts) if cuts else len(chunk)
            if not self.skipping:
                self.buffer.extend(chunk[start:end])
                if len(self.buffer) > self.limit:
                    shown = _printable(bytes(self.buffer[:200]).decode("utf-8", "replace"))
                    out.append(BadLine("", ProtocolError(
                        shown, len(shown),
                        f"a line longer than {self.limit} bytes without a line end (CR or LF): "
                        "expected USARSim lines; the rest of it is skipped")))
                    self.buffer.clear()
                    self.skipping = True
            if cuts:
                if not self.skipping and self.buffer.strip():
                    out.append(bytes(self.buffer))
                self.buffer.clear()
                self.skipping = False
                start = end + 1
            else:
                start = end
        return out
