"""A fault-injecting TCP proxy between a USARSim client and a real (embedded) USARSim server.

Each client connection gets its own connection to the server; lines are forwarded both ways and
shown to a :class:`Fault`, which may pass, rewrite, drop or replace them, slow them down, stall
the stream, or close the connection. The proxy notes when the fault first took effect (on the
system-wide monotonic clock, so a child process's timestamps compare with it).

With ``linger`` the server side stays open after the client has gone: the server then keeps the
client's robot (UDK destroys it on close), so a test can watch whether the arm holds still after
the client gave up.
"""

from __future__ import annotations

import contextlib
import queue
import socket
import threading
import time
from collections.abc import Iterable
from dataclasses import dataclass, field

from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import parse_line

# ------------------------------------------------------------------------------ write operations


@dataclass(frozen=True)
class Slow:
    """Write ``data`` one byte at a time, ``per_byte_s`` apart."""

    data: bytes
    per_byte_s: float = 0.1


class Close:
    """Close the connection (both sides)."""


class Stall:
    """Write nothing more to the client (the connection stays open)."""


Op = bytes | Slow | Close | Stall


# ------------------------------------------------------------------------------ connections


@dataclass
class Link:
    """One proxied connection and what happened on it."""

    client: socket.socket
    upstream: socket.socket | None = None
    upstream_port: int | None = None
    """The proxy's local port towards the server (the server sees the robot's owner there)."""
    connected_at: float = field(default_factory=time.monotonic)
    fault_at: float | None = None
    client_gone_at: float | None = None
    from_client: list[bytes] = field(default_factory=list)
    acts: int = 0
    first_act: tuple[float, ...] | None = None
    last_act: tuple[float, ...] | None = None
    last_act_at: float | None = None
    motion_at: float | None = None
    stalled: bool = False
    closed: bool = False
    down: queue.Queue[Op | None] = field(default_factory=queue.Queue)

    def fault(self) -> None:
        """Note that the fault takes effect now (the first time only)."""
        if self.fault_at is None:
            self.fault_at = time.monotonic()

    def in_motion(self, delay_s: float = 0.0) -> bool:
        """True once the client has been streaming a real motion for ``delay_s``."""
        return self.motion_at is not None and time.monotonic() >= self.motion_at + delay_s


def head(line: bytes) -> str:
    """The command word of a raw line ('' when there is none)."""
    text = line.split(b"{", 1)[0].strip()
    return text.decode("ascii", "replace").upper()


class Fault:
    """Forwards everything unchanged; subclasses inject one fault.

    Hooks run on the proxy's threads; they return what to write instead of the line.
    """

    name = "none"
    connect_upstream = True
    """False: accept the client but never connect to the server (and never speak)."""

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        """A complete line from the server (with its terminator)."""
        return [line]

    def client_line(self, link: Link, line: bytes) -> bytes | None:
        """A complete line from the client; None drops it."""
        return line


MOTION_THRESHOLD_RAD = 0.1
"""An ACT target this far from the first ACT's marks the start of a real motion (drive
identification swings the joints by about 0.03 rad only)."""


class FaultProxy:
    """Listens on a free loopback port and proxies each connection to ``upstream_port``.

    Args:
        upstream_port: the server's port.
        fault: what to inject.
        linger: keep the server side open after the client closes (until :meth:`close`).
    """

    def __init__(self, upstream_port: int, fault: Fault, linger: bool = False):
        self.upstream_port = upstream_port
        self.fault = fault
        self.linger = linger
        self.links: list[Link] = []
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.listen(8)
        self.port = int(self._sock.getsockname()[1])
        self._closing = threading.Event()
        threading.Thread(target=self._accept, daemon=True, name="proxy-accept").start()

    # ------------------------------------------------------------------ public
    @property
    def fault_at(self) -> float | None:
        """When the fault first took effect on any connection (time.monotonic s)."""
        times = [lk.fault_at for lk in self.links if lk.fault_at is not None]
        return min(times) if times else None

    def close(self) -> None:
        """Stop listening and close every connection."""
        self._closing.set()
        with contextlib.suppress(OSError):
            self._sock.close()
        for link in self.links:
            self._close_link(link, upstream_too=True)

    def __enter__(self) -> FaultProxy:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ plumbing
    def _accept(self) -> None:
        while not self._closing.is_set():
            try:
                conn, _ = self._sock.accept()
            except OSError:
                return
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            link = Link(conn)
            self.links.append(link)
            if not self.fault.connect_upstream:
                link.fault()
                threading.Thread(target=self._drain_client, args=(link,), daemon=True).start()
                continue
            try:
                link.upstream = socket.create_connection(("127.0.0.1", self.upstream_port), 5)
            except OSError:
                conn.close()
                continue
            link.upstream.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            link.upstream_port = int(link.upstream.getsockname()[1])
            for target in (self._from_server, self._to_client, self._from_client):
                threading.Thread(target=target, args=(link,), daemon=True).start()

    def _drain_client(self, link: Link) -> None:
        """Read (and ignore) what the client says until it goes away."""
        with contextlib.suppress(OSError):
            while link.client.recv(65536):
                pass
        link.client_gone_at = time.monotonic()
        with contextlib.suppress(OSError):
            link.client.close()

    def _from_server(self, link: Link) -> None:
        assert link.upstream is not None
        buffer = b""
        while True:
            try:
                chunk = link.upstream.recv(65536)
            except OSError:
                chunk = b""
            if not chunk:
                link.down.put(None)
                return
            buffer += chunk
            while b"\n" in buffer:
                line, buffer = buffer.split(b"\n", 1)
                if link.stalled or link.closed:
                    continue
                for op in self.fault.server_line(link, line + b"\n"):
                    link.down.put(op)
                    if isinstance(op, Stall):
                        link.stalled = True
                    if isinstance(op, Close):
                        link.closed = True

    def _to_client(self, link: Link) -> None:
        while True:
            op = link.down.get()
            if op is None or isinstance(op, Close):
                self._close_link(link, upstream_too=True)
                return
            if isinstance(op, Stall):
                continue
            try:
                if isinstance(op, Slow):
                    for i in range(len(op.data)):
                        link.client.sendall(op.data[i:i + 1])
                        time.sleep(op.per_byte_s)
                else:
                    link.client.sendall(op)
            except OSError:
                return

    def _from_client(self, link: Link) -> None:
        assert link.upstream is not None
        buffer = b""
        while True:
            try:
                chunk = link.client.recv(65536)
            except OSError:
                chunk = b""
            if not chunk:
                link.client_gone_at = time.monotonic()
                self._close_link(link, upstream_too=not self.linger)
                return
            buffer += chunk
            while b"\n" in buffer:
                line, buffer = buffer.split(b"\n", 1)
                line += b"\n"
                link.from_client.append(line)
                if head(line) == "ACT":
                    self._note_act(link, line)
                out = self.fault.client_line(link, line)
                if out:
                    try:
                        link.upstream.sendall(out)
                    except OSError:
                        return

    @staticmethod
    def _note_act(link: Link, line: bytes) -> None:
        link.acts += 1
        try:
            msg = parse_line(line.decode())
        except Exception:
            return
        if not isinstance(msg, m.Act):
            return
        values = tuple(v for _, v in msg.targets)
        link.last_act, link.last_act_at = values, time.monotonic()
        if link.first_act is None:
            link.first_act = values
        elif link.motion_at is None and len(values) == len(link.first_act) and max(
                abs(a - b) for a, b in zip(values, link.first_act, strict=True)
        ) > MOTION_THRESHOLD_RAD:
            link.motion_at = time.monotonic()

    def _close_link(self, link: Link, upstream_too: bool) -> None:
        with contextlib.suppress(OSError):
            link.client.shutdown(socket.SHUT_RDWR)
        with contextlib.suppress(OSError):
            link.client.close()
        if upstream_too and link.upstream is not None:
            with contextlib.suppress(OSError):
                link.upstream.shutdown(socket.SHUT_RDWR)
            with contextlib.suppress(OSError):
                link.upstream.close()


def closed_port() -> int:
    """A loopback port nobody listens on (bound, then released)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])
