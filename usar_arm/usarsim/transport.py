"""The line transport under :class:`~usar_arm.usarsim.client.UsarClient`: one TCP socket, a
reader thread that frames what arrives into text lines, and sending with a timeout.

It knows nothing of USARSim messages: every complete, decodable line goes to ``deliver`` and every
line that is not text (or too long) to ``reject``, both on the reader thread. All its state
changes happen under the condition it is given, which it notifies, so a waiter can combine its
own predicate with :attr:`LineTransport.closed_reason` and :attr:`LineTransport.bytes_received`.
"""

from __future__ import annotations

import contextlib
import logging
import select
import socket
import threading
from collections.abc import Callable

from usar_arm.core.errors import ConnectionFailedError, ConnectionLostError, ProtocolError
from usar_arm.usarsim.lines import BadLine, LineSplitter, decode_line

log = logging.getLogger("usar_arm.usarsim")
wire_log = logging.getLogger("usar_arm.usarsim.wire")

_POLL_S = 0.2
"""How often (s) the reader thread looks at the stop flag while no byte arrives."""


class LineTransport:
    """A TCP connection that reads lines on its own thread.

    Args:
        host, port: the server.
        send_timeout: seconds a ``sendall`` may block before the connection counts as lost.
        cond: the condition every state change is made under and notified on.
        deliver: called with each decoded line (no terminator) on the reader thread.
        reject: called with each line that is not USARSim text on the reader thread.
    """

    def __init__(self, host: str, port: int, send_timeout: float, cond: threading.Condition,
                 deliver: Callable[[str], None], reject: Callable[[BadLine], None]):
        self.host = host
        self.port = port
        self.send_timeout = send_timeout
        self.bytes_received = 0
        """Bytes received in all."""
        self._cond = cond
        self._deliver = deliver
        self._reject = reject
        self._splitter = LineSplitter()
        self._sock: socket.socket | None = None
        self._reader: threading.Thread | None = None
        self._send_lock = threading.Lock()
        self._stop = threading.Event()
        self._closed_reason: str | None = None
        self._on_close: list[Callable[[], None]] = []

    def open(self, connect_timeout: float) -> None:
        """Connect (waiting at most ``connect_timeout`` s) and start the reader thread."""
        if self._sock is not None:
            raise RuntimeError("this client is already connected; use one client per connection")
        try:
            sock = socket.create_connection((self.host, self.port), timeout=connect_timeout)
        except OSError as exc:
            raise ConnectionFailedError(self.host, self.port, exc.strerror or str(exc)) from exc
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.settimeout(self.send_timeout)  # bounds sendall(); reads go through select()
        self._sock = sock
        self._reader = threading.Thread(target=self._read_loop, daemon=True,
                                        name=f"usar-client-{self.host}:{self.port}")
        self._reader.start()

    def on_close(self, callback: Callable[[], None]) -> None:
        """Call ``callback`` (after notifying the condition) whenever the connection closes."""
        self._on_close.append(callback)

    def close(self) -> None:
        """Close the socket and stop the reader thread (waits up to 2 s for it)."""
        self._stop.set()
        sock, self._sock = self._sock, None
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            sock.close()
        if self._reader is not None and self._reader is not threading.current_thread():
            self._reader.join(2.0)
        self.set_closed("the client closed it")

    @property
    def is_open(self) -> bool:
        """True while the socket exists and has not closed."""
        return self._sock is not None and self._closed_reason is None

    @property
    def closed_reason(self) -> str | None:
        """Why the connection closed (None while it is open)."""
        return self._closed_reason

    @property
    def stopping(self) -> bool:
        """True once this end started closing (a close is then expected, not news)."""
        return self._stop.is_set()

    @property
    def local_port(self) -> int | None:
        """This end's TCP port (the server sees the client as host:local_port)."""
        return None if self._sock is None else int(self._sock.getsockname()[1])

    def send_line(self, text: str) -> None:
        """Send raw text; a CRLF is appended when missing.

        Raises:
            ConnectionLostError: the connection is closed, or the send failed or timed out.
        """
        if not text.endswith(("\r\n", "\n", "\r")):
            text += "\r\n"
        sock = self._sock
        if sock is None or self._closed_reason is not None:
            raise ConnectionLostError(f"sending {text.strip()[:40]}", self._closed_reason or "")
        wire_log.debug("-> %s", text.rstrip())
        try:
            with self._send_lock:
                sock.sendall(text.encode("ascii", "replace"))
        except (TimeoutError, OSError) as exc:
            self.set_closed(f"send failed: {exc}")
            raise ConnectionLostError(f"sending {text.strip()[:40]}", str(exc)) from exc

    def slow_hint(self, received_before: int) -> str:
        """'is answering too slowly ...' when bytes arrived since ``received_before`` but no
        complete line did; '' otherwise."""
        got = self.bytes_received - received_before
        if got <= 0 or self._splitter.partial == 0:
            return ""
        return (f"is answering too slowly: {got} byte(s) arrived but the line is still "
                f"unfinished ({self._splitter.partial} byte(s) of it so far)")

    def set_closed(self, reason: str) -> None:
        """Record why the connection closed (the first reason stays) and wake every waiter."""
        with self._cond:
            if self._closed_reason is None:
                self._closed_reason = reason
                if not self._stop.is_set():
                    log.warning("%s:%d: %s", self.host, self.port, reason)
            self._cond.notify_all()
        for callback in self._on_close:
            callback()

    def _read_loop(self) -> None:
        sock = self._sock
        assert sock is not None, "the reader thread starts after the socket exists"
        reason = "the server closed the connection"
        try:
            while not self._stop.is_set():
                ready, _, _ = select.select([sock], [], [], _POLL_S)
                if not ready:
                    continue
                chunk = sock.recv(65536)
                if not chunk:
                    if self._splitter.buffer.strip():
                        reason += (f" in the middle of a line ({self._splitter.partial} bytes "
                                   "unterminated)")
                    break
                with self._cond:
                    self.bytes_received += len(chunk)
                self._split(chunk)
        except (OSError, ValueError) as exc:
            if not self._stop.is_set():
                reason = f"connection error: {exc}"
        self.set_closed(reason)

    def _split(self, chunk: bytes) -> None:
        for item in self._splitter.feed(chunk):
            if isinstance(item, BadLine):
                self._reject(item)
                continue
            try:
                text = decode_line(item)
            except ProtocolError as exc:
                self._reject(BadLine("", exc))
                continue
            self._deliver(text)
