"""The embedded USARSim-compatible server: TCP on an asyncio loop, MuJoCo physics in step with it.

One asyncio loop (in the caller's thread for ``usar-arm sim``, or in a background thread when
embedded) owns everything: the listening socket, every connection, and the physics, which it
advances in frames of :data:`FRAME_S` simulated seconds, paced against the wall clock by
``speed``. Bad input from one client (malformed or oversized lines, a client vanishing mid-line)
is logged and never disturbs the others.
"""

from __future__ import annotations

import asyncio
import logging
import threading
import time
from dataclasses import dataclass

from usar_arm.errors import ProtocolError
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.robot_spec import RobotSpec, builtin_robots
from usar_arm.sim.session import Session
from usar_arm.sim.world_spec import WorldSpec, load_world
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import MAX_LINE_BYTES, format_message, parse_line
from usar_arm.usarsim.numbers import STYLES, NumberStyle

log = logging.getLogger("usar_arm.sim")
wire_log = logging.getLogger("usar_arm.sim.wire")

FRAME_S = 0.002
"""Simulated seconds per physics frame (commands are applied at frame boundaries)."""
CATCH_UP_FRAMES = 100
"""Frames (0.2 s of simulated time) the physics may run back to back to catch up with the
clock; further behind, simulated time is re-anchored (and runs slower than asked)."""
MAX_CONNECTIONS = 64
"""As UDK's ``[USARBotAPI.BotServer] MaxConnections``."""
MAX_WRITE_BUFFER = 4 * 1024 * 1024
"""A client that lets this many bytes pile up unread is disconnected."""


@dataclass(frozen=True)
class SimOptions:
    """Options of the simulator.

    Attributes:
        host, port: where to listen (port 0 picks a free port).
        speed: simulated seconds per wall-clock second.
        gravity: apply gravity.
        wire_precision: ``"udk"`` (engine number formats) or ``"full"`` (float64 round-trip).
        physics_hz: physics steps per simulated second (>= 500).
    """

    host: str = "127.0.0.1"
    port: int = 3000
    speed: float = 1.0
    gravity: bool = True
    wire_precision: str = "udk"
    physics_hz: float = 1000.0

    def __post_init__(self) -> None:
        if self.speed <= 0:
            raise ValueError(f"speed must be > 0, got {self.speed}")
        if self.wire_precision not in STYLES:
            raise ValueError(f"wire_precision must be one of {sorted(STYLES)}, "
                             f"got {self.wire_precision!r}")
        if self.physics_hz < 500:
            raise ValueError(f"physics_hz must be >= 500, got {self.physics_hz}")


class _Connection(asyncio.Protocol):
    """Line framing for one client: any of CR, LF, CRLF; partial reads; 64 KiB line cap."""

    def __init__(self, server: SimServer):
        self.server = server
        self.buffer = bytearray()
        self.skipping = False
        self.transport: asyncio.Transport | None = None
        self.session: Session | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        peer = transport.get_extra_info("peername")
        peer_text = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) else str(peer)
        if len(self.server.sessions) >= MAX_CONNECTIONS:
            log.warning("%s: refused: %d connections already (the limit)", peer_text,
                        MAX_CONNECTIONS)
            transport.close()
            return
        self.server.counter += 1
        self.server.connections.add(self)
        self.session = Session(f"c{self.server.counter}", peer_text, self.send)
        self.server.sessions[self.session.key] = self.session
        log.info("%s: connected", peer_text)
        self.send(m.GameInfo(self.server.world_spec.gametype, self.server.world_spec.level,
                             self.server.world_spec.time_limit))

    def send(self, msg: m.Message) -> None:
        if self.transport is None or self.transport.is_closing():
            return
        text = format_message(msg, self.server.style)
        wire_log.debug("-> %s %s", self.session.peer if self.session else "?", text.rstrip())
        self.transport.write(text.encode("ascii", "replace"))
        if self.transport.get_write_buffer_size() > MAX_WRITE_BUFFER:
            log.warning("%s: not reading its messages (%d bytes queued); disconnected",
                        self.session.peer if self.session else "?",
                        self.transport.get_write_buffer_size())
            self.transport.abort()

    def data_received(self, data: bytes) -> None:
        if self.session is None:
            return
        self.buffer.extend(data)
        while True:
            cut = min((i for i in (self.buffer.find(b"\n"), self.buffer.find(b"\r")) if i >= 0),
                      default=-1)
            if cut < 0:
                break
            raw = bytes(self.buffer[:cut])
            del self.buffer[: cut + 1]
            if self.skipping:
                self.skipping = False
                continue
            if raw.strip():
                self._line(raw)
        if len(self.buffer) > MAX_LINE_BYTES:
            log.warning("%s: line longer than %d bytes discarded", self.session.peer,
                        MAX_LINE_BYTES)
            self.buffer.clear()
            self.skipping = True

    def _line(self, raw: bytes) -> None:
        assert self.session is not None
        text = raw.decode("utf-8", "replace")
        wire_log.debug("<- %s %s", self.session.peer, text)
        try:
            msg = parse_line(text)
        except ProtocolError as exc:
            log.warning("%s: malformed line ignored: %s", self.session.peer, exc)
            return
        try:
            self.session.handle(msg, self.server.world, self.server.world_spec,
                                self.server.robots, self.server.style)
        except Exception:  # a bug must not take the server down for everyone
            log.exception("%s: error while handling %r", self.session.peer, text)

    def connection_lost(self, exc: Exception | None) -> None:
        self.server.connections.discard(self)
        if self.session is None:
            return
        if self.buffer:
            log.info("%s: left mid-line (%d bytes unterminated)", self.session.peer,
                     len(self.buffer))
        self.server.sessions.pop(self.session.key, None)
        if self.session.robot is not None:
            self.server.world.remove_robot(self.session.key)
        log.info("%s: disconnected%s", self.session.peer, "; robot destroyed"
                 if self.session.robot is not None else "")
        self.session = None


class SimServer:
    """The simulator. Use :meth:`start` (background thread) or :meth:`run` (this thread).

    Args:
        options: where to listen and how to simulate.
        robots: spawnable robot classes (default: the shipped ones).
        world_spec: the map (default: the shipped one).
    """

    def __init__(self, options: SimOptions | None = None,
                 robots: dict[str, RobotSpec] | None = None,
                 world_spec: WorldSpec | None = None):
        self.options = options or SimOptions()
        self.robots = robots if robots is not None else builtin_robots()
        self.world_spec = world_spec or load_world()
        self.style: NumberStyle = STYLES[self.options.wire_precision]
        self.world = PhysicsWorld(timestep=1.0 / self.options.physics_hz,
                                  gravity=self.options.gravity)
        self.sessions: dict[str, Session] = {}
        self.connections: set[_Connection] = set()
        self.counter = 0
        self.port: int | None = None
        self._steps_per_frame = max(1, round(FRAME_S * self.options.physics_hz))
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._failure: BaseException | None = None

    # ------------------------------------------------------------------ lifecycle
    async def serve(self) -> None:
        """Listen and simulate until :meth:`stop` is called."""
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        server = await self._loop.create_server(lambda: _Connection(self), self.options.host,
                                                self.options.port, reuse_address=True)
        self.port = server.sockets[0].getsockname()[1]
        log.info("listening on %s:%d", self.options.host, self.port)
        self._ready.set()
        physics = asyncio.create_task(self._physics())
        try:
            await self._stop.wait()
        finally:
            physics.cancel()
            server.close()
            for conn in list(self.connections):
                if conn.transport is not None:
                    conn.transport.abort()
            await server.wait_closed()
            log.info("stopped; port %d released", self.port)

    def run(self) -> None:
        """Serve in the calling thread until :meth:`stop` (or KeyboardInterrupt)."""
        asyncio.run(self.serve())

    def start(self, timeout: float = 10.0) -> int:
        """Serve in a background thread; return the port once listening."""
        def target() -> None:
            try:
                asyncio.run(self.serve())
            except BaseException as exc:  # surfaced by start()
                self._failure = exc
                self._ready.set()

        self._thread = threading.Thread(target=target, name="usar-arm-sim", daemon=True)
        self._thread.start()
        if not self._ready.wait(timeout):
            raise TimeoutError(f"simulator did not start listening within {timeout} s")
        if self._failure is not None:
            raise self._failure
        assert self.port is not None
        return self.port

    def stop_from_loop(self) -> None:
        """Stop serving; call from the server's own loop (signal handlers)."""
        if self._stop is not None:
            self._stop.set()

    def stop(self, timeout: float = 10.0) -> None:
        """Stop serving, close every connection and free the port."""
        loop, stop = self._loop, self._stop
        if loop is not None and stop is not None and not loop.is_closed():
            try:
                loop.call_soon_threadsafe(stop.set)
            except RuntimeError:
                pass  # loop already closed
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    def __enter__(self) -> SimServer:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ------------------------------------------------------------------ physics
    async def _physics(self) -> None:
        loop = asyncio.get_running_loop()
        speed = self.options.speed
        wall0, sim0 = loop.time(), self.world.time
        behind_logged = False
        while True:
            target = sim0 + (loop.time() - wall0) * speed
            frames = 0
            while self.world.time + FRAME_S / 2 <= target and frames < CATCH_UP_FRAMES:
                self._frame()
                frames += 1
            if frames == CATCH_UP_FRAMES:  # far behind: re-anchor rather than spiral
                if not behind_logged:
                    log.warning("physics cannot keep up with --speed %g; simulated time now "
                                "runs slower than asked", speed)
                    behind_logged = True
                wall0, sim0 = loop.time(), self.world.time
            wait = wall0 + (self.world.time + FRAME_S - sim0) / speed - loop.time()
            await asyncio.sleep(max(0.0, wait))

    def _frame(self) -> None:
        for session in list(self.sessions.values()):
            if session.pending is not None:
                session.spawn_pending(self.world)
        self.world.step(self._steps_per_frame)
        for session in list(self.sessions.values()):
            try:
                session.status(self.world, self.style)
            except Exception:
                log.exception("%s: error while sending status", session.peer)


def wait_for_port(host: str, port: int, timeout: float = 5.0) -> None:
    """Block until something accepts TCP connections at host:port (for scripts and tests)."""
    import socket

    deadline = time.monotonic() + timeout
    while True:
        try:
            with socket.create_connection((host, port), timeout=0.5):
                return
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)
