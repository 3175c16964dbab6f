"""The embedded USARSim-compatible server: TCP on an asyncio loop, MuJoCo physics in step with it.

One asyncio loop (in the caller's thread for ``usar-arm sim``, or in a background thread when
embedded) owns everything: the listening socket, every connection (:mod:`usar_arm.sim.connection`),
and the physics, which it advances in frames of :data:`FRAME_S` simulated seconds, paced against
the wall clock by ``speed``. Bad input from one client (malformed, oversized or binary lines, a
flood of lines, a client vanishing mid-line) is counted, logged and never disturbs the others.
"""

from __future__ import annotations

import asyncio
import heapq
import logging
import math
import threading
import time
from dataclasses import dataclass

from usar_arm.sim.connection import MAX_WRITE_BUFFER, Connection
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.robot_session import Session
from usar_arm.sim.robot_spec import RobotSpec, builtin_robots
from usar_arm.sim.truth import EffectorTruth, Truth, in_base_link, tool0_in_base
from usar_arm.sim.world_spec import WorldSpec, load_world
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import STYLES, NumberStyle

__all__ = ["MAX_CONNECTIONS", "MAX_WRITE_BUFFER", "ClientInfo", "SimOptions", "SimServer",
           "Truth", "wait_for_port"]

log = logging.getLogger("usar_arm.sim")

FRAME_S = 0.002
"""Simulated seconds per physics frame (commands are applied at frame boundaries)."""
CATCH_UP_FRAMES = 100
"""Frames (0.2 s of simulated time) the physics may fall behind the clock and catch up; further
behind, simulated time is re-anchored (and runs slower than asked)."""
PHYSICS_TURN_S = 0.005
"""Wall seconds of frames the physics runs back to back (when catching up) before it lets the
connections have a turn."""
BEHIND_LOG_INTERVAL_S = 30.0
"""Wall seconds between repeated "physics cannot keep up" warnings."""
MAX_CONNECTIONS = 64
"""As UDK's ``[USARBotAPI.BotServer] MaxConnections``."""


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


@dataclass(frozen=True)
class ClientInfo:
    """A connected client: the server's key, its address, whether it has spawned a robot,
    how many bytes of replies wait in its socket's buffer, and how many bytes it has sent."""

    key: str
    peer: str
    has_robot: bool
    queued_bytes: int
    received_bytes: int = 0


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
        self.robots = robots if robots is not None else builtin_robots(vehicles=True)
        self.world_spec = world_spec or load_world()
        self.style: NumberStyle = STYLES[self.options.wire_precision]
        self.world = PhysicsWorld(timestep=1.0 / self.options.physics_hz,
                                  gravity=self.options.gravity,
                                  scenery=self.world_spec.boxes, floor_z=self.world_spec.floor_z,
                                  cell=self.world_spec.cell)
        self.max_connections = MAX_CONNECTIONS
        self._clients: dict[str, Connection] = {}
        """Session key -> the connection that owns the session (``connection.session``)."""
        self._joined = 0
        self._leaving: list[str] = []
        """Keys of robots whose connection closed, destroyed at the next physics frame."""
        self._lock = threading.RLock()
        """Held by the loop thread while it changes the physics or a session, and by
        :meth:`truth` / :meth:`clients` while they read them from another thread."""
        self._status_due: list[tuple[float, str]] = []
        """(simulated time, session key) of the next status of every robot (a heap)."""
        self.behind_count = 0
        """How often the physics fell so far behind the clock that simulated time slowed."""
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
        server = await self._loop.create_server(lambda: Connection(self), self.options.host,
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
            for conn in list(self._clients.values()):
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

    # ------------------------------------------------------------------ clients
    def join(self, client: Connection, peer: str) -> Session | None:
        """Register a new client and greet it (NFO); None when the server is full."""
        with self._lock:
            if len(self._clients) >= self.max_connections:
                log.warning("%s: refused: %d connections already (the limit)", peer,
                            self.max_connections)
                return None
            self._joined += 1
            session = Session(f"c{self._joined}", peer, client.send)
            self._clients[session.key] = client
        log.info("%s: connected", peer)
        spec = self.world_spec
        client.send(m.GameInfo(spec.gametype, spec.level, spec.time_limit))
        return session

    def leave(self, session: Session) -> None:
        """Forget a client; its robot is destroyed at the next physics frame."""
        with self._lock:
            self._clients.pop(session.key, None)
            if session.robot is not None:
                self._leaving.append(session.key)
            if session.world_controller is not None:
                session.world_controller.close(self.world)

    def handle(self, session: Session, msg: m.Message) -> None:
        """Act on one message of a client (the loop thread, between physics frames)."""
        with self._lock:
            session.handle(msg, self.world, self.world_spec, self.robots, self.style,
                           self._find_robot)

    def _find_robot(self, name: str) -> str | None:
        """The key of the robot INIT named ``name`` (exactly, as ``GetBotController``)."""
        for conn in self._clients.values():
            session = conn.session
            if session is not None and session.robot is not None and session.robot_name == name:
                return session.key
        return None

    def clients(self) -> list[ClientInfo]:
        """The connected clients, read consistently from any thread."""
        with self._lock:
            out = []
            for key, conn in self._clients.items():
                session, transport = conn.session, conn.transport
                if session is None:
                    continue
                queued = transport.get_write_buffer_size() if transport is not None else 0
                out.append(ClientInfo(key, session.peer, session.robot is not None, queued,
                                      session.rejections.bytes_in))
            return out

    @property
    def cell(self) -> str:
        """Its world's work cell: the ``cell:`` of the world file (a shipped cell's name or a
        file, the one description the planner reads as a scene), or "" when it has none."""
        return self.world_spec.cell_name

    def truth(self, peer_port: int) -> Truth | None:
        """The true state (joints, tool0 in base_link) of the robot of the client whose
        address ends in ``:peer_port``, from the simulator's spec and physics under the lock
        (None when that client has no robot)."""
        with self._lock:
            for conn in self._clients.values():
                session = conn.session
                if session is None or session.robot is None:
                    continue
                if not session.peer.endswith(f":{peer_port}"):
                    continue
                world, key = self.world, session.key
                platform = world.platform_pose(key)
                joints, tool0 = {}, {}
                for act in session.robot.actuators:
                    joints[act.name] = world.joint_values(key, act.name)
                    tool0[act.name] = tool0_in_base(act, platform, world.tip_pose(key, act.name))
                tools = {}
                for tool in world.rig.tools.values():
                    if tool.key == key:
                        pose = in_base_link(platform, world.rig.tool_pose(world.data, tool))
                        tools[tool.spec.name] = EffectorTruth(
                            tool.spec.name, tool.holder is not None,
                            tool.holder.spec.name if tool.holder else None,
                            tool.held.name if tool.held else None, pose)
                return Truth(key, session.peer, world.time, joints, tool0, tools,
                             world.contacts.history(key))
        return None

    # ------------------------------------------------------------------ physics
    async def _physics(self) -> None:
        loop = asyncio.get_running_loop()
        speed = self.options.speed
        world = self.world
        wall0, sim0 = loop.time(), world.time
        logged_wall, logged_sim = -math.inf, 0.0
        while True:
            now = loop.time()
            target = sim0 + (now - wall0) * speed
            if target - world.time > CATCH_UP_FRAMES * FRAME_S:  # far behind: re-anchor
                self.behind_count += 1
                if now - logged_wall >= BEHIND_LOG_INTERVAL_S:
                    ratio = "" if logged_wall == -math.inf else (
                        f" (simulated time ran at "
                        f"{(world.time - logged_sim) / (now - logged_wall):.2f}x the wall "
                        f"clock over the last {now - logged_wall:.0f} s)")
                    log.warning("physics cannot keep up with --speed %g with %d robot(s); "
                                "simulated time now runs slower than asked%s", speed,
                                len(world.robot_keys), ratio)
                    logged_wall, logged_sim = now, world.time
                wall0, sim0 = now, world.time
                target = sim0
            turn_end = time.perf_counter() + PHYSICS_TURN_S
            while world.time + FRAME_S / 2 <= target:
                self._frame()
                if time.perf_counter() > turn_end:
                    break  # behind: let the connections run, then go on
            wait = wall0 + (world.time + FRAME_S - sim0) / speed - loop.time()
            await asyncio.sleep(max(0.0, wait))

    def _frame(self) -> None:
        with self._lock:
            self._frame_locked()

    def _frame_locked(self) -> None:
        world = self.world
        sessions = [c.session for c in self._clients.values() if c.session is not None]
        spawning = [s for s in sessions if s.pending is not None]
        if spawning or self._leaving:
            try:
                with world.batch():  # one model rebuild for all of them
                    for key in self._leaving:
                        world.remove_robot(key)
                    self._leaving.clear()
                    for session in spawning:
                        session.spawn_pending(world)
            except Exception:  # the physics must go on for everyone else
                log.exception("spawning %s failed", ", ".join(s.peer for s in spawning))
                for session in spawning:
                    session.pending = session.robot = None
                self._leaving.clear()
                spawning = []
            for session in spawning:
                heapq.heappush(self._status_due, (session.next_status, session.key))
        world.step(self._steps_per_frame)
        due = self._status_due
        while due and due[0][0] <= world.time + 1e-9:
            _, key = heapq.heappop(due)
            conn = self._clients.get(key)
            client = conn.session if conn is not None else None
            if client is None or client.robot is None:
                continue  # gone
            session = client
            try:
                msgs = session.status(world)
                conn.send_all(msgs)  # type: ignore[union-attr]
            except Exception:
                log.exception("%s: error while sending status", session.peer)
                msgs = []
            heapq.heappush(due, (session.next_status, key))
            if not msgs:
                break  # not due after all (a clock step backwards): never spin


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
