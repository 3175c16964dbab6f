"""Request/reply matching and stream waits: the middle part of the USARSim client.

:class:`Exchange` owns a :class:`~usar_arm.usarsim.transport.LineTransport` (socket, reader
thread, framing) and an :class:`~usar_arm.usarsim.inbox.Inbox` (parsed lines routed to replies and
per-component caches), and turns waiting on them into results or errors that say what the server
did: nothing, too little, a line that is not USARSim, or a close. Requests go one at a time.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable

from usar_arm.core.errors import (
    ConnectionLostError,
    ProtocolError,
    ResponseTimeoutError,
    UnknownComponentError,
    UsarArmError,
)
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import format_message
from usar_arm.usarsim.inbox import STATUS_HEADS, Inbox, Received, Subscriber
from usar_arm.usarsim.lines import BadLine
from usar_arm.usarsim.transport import LineTransport

log = logging.getLogger("usar_arm.usarsim")

DEFAULT_TIMEOUT_S = 5.0
"""Default time to wait for a reply (s)."""


class Exchange:
    """Requests, replies and stream waits over one connection to a USARSim server.

    Args:
        host, port: the server (UDK default port 3000).
        timeout: default seconds to wait for any reply.
        connect_timeout: seconds to wait for the TCP connection and the NFO greeting (default:
            ``timeout``).

    The connection itself (greeting, close) and the robot commands are
    :class:`~usar_arm.usarsim.client.UsarClient`'s.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 3000,
                 timeout: float = DEFAULT_TIMEOUT_S, connect_timeout: float | None = None):
        self.host = host
        self.port = port
        self.timeout = timeout
        self.connect_timeout = timeout if connect_timeout is None else connect_timeout
        self._cond = threading.Condition(threading.RLock())
        self._inbox = Inbox(self._cond, f"{host}:{port}")
        self._wire = LineTransport(host, port, timeout, self._cond, self._inbox.deliver,
                                   self._inbox.reject)
        self._wire.on_close(self._inbox.wake)
        self._request_lock = threading.Lock()

    @property
    def game_info(self) -> m.GameInfo | None:
        """The server's NFO greeting (None before it arrived)."""
        return self._inbox.game_info

    @property
    def bad_lines(self) -> list[BadLine]:
        """Lines from the server that were not USARSim (the latest 100), oldest first."""
        return self._inbox.bad_lines

    @property
    def bad_line_count(self) -> int:
        """How many lines that were not USARSim arrived in all."""
        return self._inbox.bad_line_count

    @property
    def bytes_received(self) -> int:
        """Bytes received in all."""
        return self._wire.bytes_received

    @property
    def local_port(self) -> int | None:
        """This end's TCP port (the server sees the client as host:local_port)."""
        return self._wire.local_port

    @property
    def connected(self) -> bool:
        """True while the connection is open."""
        return self._wire.is_open

    @property
    def closed_reason(self) -> str | None:
        """Why the connection closed (None while it is open)."""
        return self._wire.closed_reason

    # ------------------------------------------------------------------ sending
    def send(self, msg: m.Message) -> None:
        """Send one message (full float precision)."""
        self._wire.send_line(format_message(msg))

    def send_line(self, text: str) -> None:
        """Send raw text; a CRLF is appended when missing."""
        self._wire.send_line(text)

    # ------------------------------------------------------------------ streams
    def subscribe(self, callback: Subscriber) -> Callable[[], None]:
        """Call ``callback`` (on the reader thread) for every unsolicited line; returns an
        unsubscribe function. Callbacks must be quick."""
        return self._inbox.subscribe(callback)

    def latest(self, kind: str, name: str) -> Received | None:
        """The latest ``kind`` (ASTA, SEN, EFF) line of component ``name``, with its printed
        precision (:attr:`Received.steps`)."""
        return self._inbox.latest(kind, name)

    def latest_asta(self, actuator: str) -> m.Asta | None:
        """The most recent ASTA of ``actuator``, if any arrived."""
        rec = self._inbox.latest("ASTA", actuator)
        return rec.message if rec is not None and isinstance(rec.message, m.Asta) else None

    def latest_sen(self, sensor: str) -> m.Sen | None:
        """The most recent SEN of ``sensor``, if any arrived."""
        rec = self._inbox.latest("SEN", sensor)
        return rec.message if rec is not None and isinstance(rec.message, m.Sen) else None

    def latest_line(self, kind: str, name: str) -> str | None:
        """The raw text of the latest ``kind`` (ASTA, SEN, EFF) line of component ``name``."""
        rec = self._inbox.latest(kind, name)
        return rec.line if rec else None

    def wait_asta(self, actuator: str, after_time: float | None = None,
                  timeout: float | None = None) -> m.Asta:
        """Wait for an ASTA of ``actuator`` with simulated time > ``after_time``."""
        msg = self.wait_stream("ASTA", actuator, after_time, timeout).message
        assert isinstance(msg, m.Asta), "the ASTA cache holds ASTA lines"
        return msg

    def wait_sen(self, sensor: str, after_time: float | None = None,
                 timeout: float | None = None) -> m.Sen:
        """Wait for a SEN of ``sensor`` with simulated time > ``after_time``."""
        msg = self.wait_stream("SEN", sensor, after_time, timeout).message
        assert isinstance(msg, m.Sen), "the SEN cache holds SEN lines"
        return msg

    def wait_stream(self, kind: str, name: str, after_time: float | None = None,
                    timeout: float | None = None) -> Received:
        """Wait for a ``kind`` (ASTA, SEN, EFF) line of ``name`` with simulated time >
        ``after_time`` (any, when None) and return it with its printed precision.

        Raises:
            ProtocolError: a line of that kind (or an unrecognisable one) was not USARSim.
            ResponseTimeoutError: none came within the timeout (names the known components).
            ConnectionLostError: the connection closed while waiting.
        """
        limit = self.timeout if timeout is None else timeout
        what = f"{kind} from {'sensor' if kind == 'SEN' else 'actuator'} {name}"
        key, inbox = (kind, name), self._inbox

        def fatal(head: str) -> bool:
            return head in ("", kind)

        with self._cond:
            count, received = inbox.bad_line_count, self.bytes_received
            ok = self._cond.wait_for(lambda: inbox.newer(key, after_time) is not None
                                     or self.closed_reason is not None
                                     or inbox.bad_since(count, fatal) is not None, limit)
            rec = inbox.newer(key, after_time)
            if rec is not None:
                return rec
            bad = inbox.bad_since(count, fatal) or inbox.bad_since(count, lambda h: True)
        if bad is not None:
            raise in_context(bad.error, f"while waiting for {what}, the server sent a line "
                                         "that is not USARSim")
        if not ok:
            raise ResponseTimeoutError(what, limit, self._wire.slow_hint(received) or (
                "known components: " + (", ".join(inbox.known_components()) or "(none yet)")))
        raise ConnectionLostError(f"waiting for {what}", self.closed_reason or "")

    def known_components(self) -> list[str]:
        """``Type Name`` of every component seen in the streams or replies so far."""
        return self._inbox.known_components()

    # ------------------------------------------------------------------ requests
    def request(self, msg: m.Message, accept: Callable[[m.Message], bool],
                timeout: float | None = None, describe: str | None = None) -> Received:
        """Send ``msg`` and wait for a reply line that ``accept`` takes.

        Raises:
            UnknownComponentError: a GETCONF/GETGEO got no reply (UDK's answer to "no match").
            ResponseTimeoutError: any other request got no reply.
            ConnectionLostError: the connection closed while waiting.
        """
        limit = self.timeout if timeout is None else timeout
        what = describe or format_message(msg).strip()
        inbox = self._inbox
        with self._request_lock:
            inbox.drop_stale_replies()
            count, received = inbox.bad_line_count, self.bytes_received
            self.send(msg)
            deadline = time.monotonic() + limit
            while True:
                remaining = deadline - time.monotonic()
                bad = inbox.bad_since(count, lambda head: head not in STATUS_HEADS)
                if bad is not None:
                    raise in_context(bad.error, f"the reply to `{what}` is not USARSim")
                closed = self.closed_reason
                try:  # (a reply that came before the close still answers: drain first)
                    rec = (inbox.replies.get_nowait() if closed is not None
                           else inbox.replies.get(timeout=max(0.0, remaining)))
                except queue.Empty:
                    if closed is not None:
                        raise ConnectionLostError(f"waiting for the reply to `{what}`",
                                                  closed) from None
                    raise self._no_reply(msg, what, limit, count, received) from None
                if rec is None:
                    continue  # woken by a close or a bad line; re-checked above
                if accept(rec.message):
                    inbox.note_components(rec.message)
                    return rec
                log.debug("discarding a reply that does not answer `%s`: %s", what, rec.line)

    def _no_reply(self, msg: m.Message, what: str, limit: float, count: int, received: int
                  ) -> UsarArmError:
        """The error for a request that got no reply within ``limit`` s."""
        bad = self._inbox.bad_since(count, lambda head: True)
        if bad is not None:
            return in_context(bad.error, f"no reply to `{what}` within {limit:g} s; meanwhile "
                                          "the server sent a line that is not USARSim")
        slow = self._wire.slow_hint(received)
        if slow:
            return ResponseTimeoutError(f"reply to `{what}`", limit, f"the server {slow}")
        if isinstance(msg, (m.GetConf, m.GetGeo)):
            return UnknownComponentError(what, limit, self.known_components())
        return ResponseTimeoutError(f"reply to `{what}`", limit,
                                    "the server has sent nothing at all since the request"
                                    if received == self.bytes_received else "")


def in_context(error: ProtocolError, context: str) -> ProtocolError:
    """``error`` again, its reason prefixed by what the client was doing."""
    return ProtocolError(error.line, error.position, f"{context}: {error.reason}")
