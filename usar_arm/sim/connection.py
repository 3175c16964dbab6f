"""One TCP connection of the simulator: line framing, fair scheduling, the ACT fast path.

Framing follows UDK's ``MessageParser.uc`` (docs/protocol.md section 2): a line ends at any CR
or LF, empty lines are skipped, a partial line waits for its terminator. Lines longer than
:data:`~usar_arm.usarsim.codec.MAX_LINE_BYTES` are refused whole (their tail is skipped up to the
next terminator), lines with control bytes are refused as binary, and lines that do not parse are
refused as malformed; each refusal is counted and logged through the session's throttled log.

Fairness: a connection handles its lines for at most :data:`TURN_BUDGET_S` of CPU per turn of the
event loop; with lines left over it stops reading (TCP pushes back on the sender) and takes its
next turn after every other connection and the physics have had theirs. One client flooding the
server therefore gets the CPU that is left, not the CPU of the others.
"""

from __future__ import annotations

import asyncio
import functools
import logging
import math
import re
import time
from collections import deque
from typing import Protocol

from usar_arm.core.errors import ProtocolError
from usar_arm.sim.robot_session import Session
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import MAX_LINE_BYTES, format_message, parse_line
from usar_arm.usarsim.numbers import NumberStyle


class Host(Protocol):
    """What a connection needs of the server that accepted it (``SimServer``)."""

    style: NumberStyle

    def join(self, client: Connection, peer: str) -> Session | None:
        """A new session for the client at ``peer``, or None when the server is full."""

    def leave(self, session: Session) -> None:
        """The session's client is gone (its robot is destroyed at the next frame)."""

    def handle(self, session: Session, msg: m.Message) -> None:
        """Act on one message of the session's client."""

log = logging.getLogger("usar_arm.sim")
wire_log = logging.getLogger("usar_arm.sim.wire")

MAX_WRITE_BUFFER = 4 * 1024 * 1024
"""A client that lets this many bytes pile up unread is disconnected."""
TURN_BUDGET_S = 0.002
"""CPU seconds one connection may spend on its lines before letting the others run."""

_TERMINATORS = re.compile(rb"[\r\n]+")
_BINARY = re.compile(rb"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")
# The canonical ACT line (as RosSim, Iridium and usar-arm write it); anything else takes the
# general parser. Keys are case-sensitive as in UDK; the command word is not.
_FAST_ACT = re.compile(rb"[ \t]*[Aa][Cc][Tt] \{Name ([^{}\s]+)\}"
                       rb"((?: \{Link -?[0-9]+\} \{Value [^{}\s]+\})+)[ \t]*")


_REPLIES = (m.Conf, m.PlatformConf, m.Geo, m.StartPoses, m.GameInfo)


@functools.lru_cache(maxsize=256)
def _format_reply(msg: m.Message, style: NumberStyle) -> str:
    """The text of a reply; replies repeat (same robot, same request), so each is printed once."""
    return format_message(msg, style)


def fast_act(raw: bytes) -> m.Act | None:
    """The :class:`~usar_arm.usarsim.messages.Act` of a canonical ACT line, exactly as
    :func:`~usar_arm.usarsim.codec.parse_line` gives it, or None for any other line (then the
    general parser decides)."""
    match = _FAST_ACT.fullmatch(raw)
    if match is None:
        return None
    # " {Link 0} {Value 0.5} {Link 1} ..." -> [b"Link", b"0", b"Value", b"0.5", b"Link", ...]
    tokens = match.group(2).replace(b"{", b" ").replace(b"}", b" ").split()
    try:
        pairs = tuple(zip(map(int, tokens[1::4]), map(float, tokens[3::4]), strict=True))
    except ValueError:
        return None  # let the general parser explain what is wrong
    if not all(map(math.isfinite, (v for _, v in pairs))):
        return None  # the general parser decides about nan and inf
    return m.Act(match.group(1).decode("utf-8", "replace"), pairs)


class Connection(asyncio.Protocol):
    """The protocol object of one client; owns its :class:`Session`."""

    def __init__(self, server: Host):
        self.server = server
        self.partial = bytearray()
        self.skipping = False
        self.lines: deque[bytes] = deque()
        self.paused = False
        self.transport: asyncio.Transport | None = None
        self.session: Session | None = None
        self.since = time.monotonic()

    # ------------------------------------------------------------------ lifecycle
    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        peer = transport.get_extra_info("peername")
        peer_text = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) else str(peer)
        self.session = self.server.join(self, peer_text)
        if self.session is None:
            transport.close()

    def connection_lost(self, exc: Exception | None) -> None:
        session, self.session = self.session, None
        if session is None:
            return
        self.server.leave(session)
        if self.partial and not self.skipping:
            session.rejections.count("unterminated at disconnect")
            log.info("%s: left mid-line (%d bytes unterminated)", session.peer, len(self.partial))
        if self.lines:
            session.rejections.count("unread at disconnect", len(self.lines))
        log.info("%s: disconnected after %.1f s%s; %s", session.peer,
                 time.monotonic() - self.since,
                 "; robot destroyed" if session.robot is not None else "",
                 session.rejections.summary())
        self.lines.clear()

    # ------------------------------------------------------------------ output
    def send(self, msg: m.Message) -> None:
        """Write one message (numbers in the server's style)."""
        self.send_all((msg,))

    def send_all(self, msgs: tuple[m.Message, ...] | list[m.Message]) -> None:
        """Write messages in one transport write."""
        transport = self.transport
        if transport is None or transport.is_closing() or not msgs:
            return
        style = self.server.style
        text = "".join(_format_reply(msg, style) if isinstance(msg, _REPLIES)
                       else format_message(msg, style) for msg in msgs)
        if wire_log.isEnabledFor(logging.DEBUG):
            for line in text.splitlines():
                wire_log.debug("-> %s %s", self.session.peer if self.session else "?", line)
        transport.write(text.encode("ascii", "replace"))
        if transport.get_write_buffer_size() > MAX_WRITE_BUFFER:
            log.warning("%s: not reading its messages (%d bytes queued); disconnected",
                        self.session.peer if self.session else "?",
                        transport.get_write_buffer_size())
            transport.abort()

    # ------------------------------------------------------------------ input
    def data_received(self, data: bytes) -> None:
        session = self.session
        if session is None:
            return
        session.rejections.bytes_in += len(data)
        if _TERMINATORS.search(data) is None:  # no line ends here: keep collecting
            if not self.skipping:
                self.partial += data
                self._check_oversized()
            return
        if self.partial:
            data = bytes(self.partial) + data
            self.partial.clear()
        pieces = _TERMINATORS.split(data)
        tail = pieces.pop()
        if self.skipping:  # the tail of a refused oversized line
            pieces[0] = b""
            self.skipping = False
        rejections = session.rejections
        for piece in pieces:
            if len(piece) > MAX_LINE_BYTES:
                rejections.received += 1
                rejections.reject("oversized", "line of %d bytes refused (the limit is %d)",
                                  len(piece), MAX_LINE_BYTES)
            elif piece and not piece.isspace():
                rejections.received += 1
                self.lines.append(piece)
        self.partial += tail
        self._check_oversized()
        self._drain()

    def _check_oversized(self) -> None:
        if len(self.partial) > MAX_LINE_BYTES:
            assert self.session is not None
            self.session.rejections.received += 1
            self.session.rejections.reject(
                "oversized", "line longer than %d bytes refused (its rest is skipped up to the "
                "next line end)", MAX_LINE_BYTES)
            self.partial.clear()
            self.skipping = True

    def _drain(self) -> None:
        """Handle queued lines for one turn; reschedule (and stop reading) if some are left."""
        if self.session is None:
            self.lines.clear()
            return
        deadline = time.perf_counter() + TURN_BUDGET_S
        lines = self.lines
        while lines:
            self._line(lines.popleft())
            if self.session is None or time.perf_counter() > deadline:
                break
        transport = self.transport
        if transport is None or transport.is_closing():
            return
        if lines and self.session is not None:
            if not self.paused:
                self.paused = True
                transport.pause_reading()
            asyncio.get_running_loop().call_soon(self._drain)
        elif self.paused:
            self.paused = False
            transport.resume_reading()

    def _line(self, raw: bytes) -> None:
        session = self.session
        assert session is not None
        if wire_log.isEnabledFor(logging.DEBUG):
            wire_log.debug("<- %s %s", session.peer, raw.decode("utf-8", "replace"))
        msg: m.Message | None = fast_act(raw)
        if msg is None:
            if _BINARY.search(raw) is not None:
                session.rejections.reject("binary", "line with control bytes refused: %r",
                                          raw[:60])
                return
            try:
                msg = parse_line(raw.decode("utf-8", "replace"))
            except ProtocolError as exc:
                session.rejections.reject("malformed", "malformed line ignored: %s", exc)
                return
        rejections = session.rejections
        refused = rejections.total
        try:
            self.server.handle(session, msg)
        except Exception:  # a bug must not take the server down for everyone
            log.exception("%s: error while handling %r", session.peer, raw[:200])
            rejections.count("server error")
        if rejections.total == refused:
            rejections.served += 1
