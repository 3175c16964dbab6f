"""A TCP client for USARSim (UDK) servers: line framing, requests with timeouts, streams.

A background thread reads the socket, splits lines at any of CR, LF or CRLF (partial reads and
several lines per read are fine), parses them and routes them: replies (NFO, CONF, GEO) to the
request waiting for one, unsolicited status (ASTA, STA, SEN, EFF) to per-component caches and to
subscribers. Every wait has a timeout. Requests are sent one at a time, as NIST's RosSim did.

UDK sends **no reply** to a GETCONF/GETGEO that matches nothing, and none to INIT; the client turns
those silences into errors that name what the server does know.
"""

from __future__ import annotations

import contextlib
import logging
import queue
import select
import socket
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from usar_arm.errors import (
    ConnectionFailedError,
    ConnectionLostError,
    ProtocolError,
    ResponseTimeoutError,
    UnknownComponentError,
    UnknownRobotError,
)
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import MAX_LINE_BYTES, format_message, parse_line

log = logging.getLogger("usar_arm.usarsim")
wire_log = logging.getLogger("usar_arm.usarsim.wire")

DEFAULT_TIMEOUT_S = 5.0
"""Default time to wait for a reply (s)."""


@dataclass(frozen=True)
class Received:
    """A line received from the server: its text (no terminator), the message, and when."""

    line: str
    message: m.Message
    wall_time: float


Subscriber = Callable[[Received], None]
_STREAMS = (m.Asta, m.Sta, m.Sen, m.Eff)


class UsarClient:
    """A connection to one USARSim server (one robot per connection).

    Args:
        host, port: the server (UDK default port 3000).
        timeout: default seconds to wait for any reply.
        connect_timeout: seconds to wait for the TCP connection and the NFO greeting.

    Use as a context manager, or call :meth:`connect` and :meth:`close`.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 3000,
                 timeout: float = DEFAULT_TIMEOUT_S, connect_timeout: float = 5.0):
        self.host = host
        self.port = port
        self.timeout = timeout
        self.connect_timeout = connect_timeout
        self.game_info: m.GameInfo | None = None
        self._sock: socket.socket | None = None
        self._reader: threading.Thread | None = None
        self._replies: queue.Queue[Received | None] = queue.Queue()
        self._request_lock = threading.Lock()
        self._send_lock = threading.Lock()
        self._cond = threading.Condition()
        self._closed_reason: str | None = None
        self._stop = threading.Event()
        self._subscribers: list[Subscriber] = []
        self._latest: dict[tuple[str, str], Received] = {}
        self._components: dict[str, None] = {}
        self._stream_count = 0
        self._first_status: Received | None = None

    # ------------------------------------------------------------------ connection
    def connect(self) -> m.GameInfo:
        """Open the connection and wait for the server's NFO greeting."""
        if self._sock is not None:
            raise RuntimeError("this client is already connected; use one client per connection")
        try:
            sock = socket.create_connection((self.host, self.port), timeout=self.connect_timeout)
        except OSError as exc:
            raise ConnectionFailedError(self.host, self.port, exc.strerror or str(exc)) from exc
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.settimeout(self.timeout)  # bounds sendall(); reads go through select()
        self._sock = sock
        self._reader = threading.Thread(target=self._read_loop, daemon=True,
                                        name=f"usar-client-{self.host}:{self.port}")
        self._reader.start()
        with self._cond:
            ok = self._cond.wait_for(lambda: self.game_info is not None or self._closed_reason,
                                     self.connect_timeout)
        if self.game_info is None:
            self.close()
            if not ok:
                raise ResponseTimeoutError(
                    "NFO greeting", self.connect_timeout,
                    f"{self.host}:{self.port} accepted the connection but is not talking USARSim")
            raise ConnectionLostError("waiting for the NFO greeting", self._closed_reason or "")
        log.info("connected to %s:%d (%s, %s)", self.host, self.port, self.game_info.gametype,
                 self.game_info.level)
        return self.game_info

    def close(self) -> None:
        """Close the connection (the server then destroys this connection's robot)."""
        self._stop.set()
        sock, self._sock = self._sock, None
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            sock.close()
        if self._reader is not None and self._reader is not threading.current_thread():
            self._reader.join(2.0)
        self._set_closed("the client closed it")

    def __enter__(self) -> UsarClient:
        if self._sock is None:
            self.connect()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def local_port(self) -> int | None:
        """This end's TCP port (the server sees the client as host:local_port)."""
        return None if self._sock is None else int(self._sock.getsockname()[1])

    @property
    def connected(self) -> bool:
        """True while the connection is open."""
        return self._sock is not None and self._closed_reason is None

    # ------------------------------------------------------------------ sending
    def send(self, msg: m.Message) -> None:
        """Send one message (full float precision)."""
        self.send_line(format_message(msg))

    def send_line(self, text: str) -> None:
        """Send raw text; a CRLF is appended when missing."""
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
            self._set_closed(f"send failed: {exc}")
            raise ConnectionLostError(f"sending {text.strip()[:40]}", str(exc)) from exc

    # ------------------------------------------------------------------ reading
    def _read_loop(self) -> None:
        buffer = bytearray()
        sock = self._sock
        assert sock is not None
        reason = "the server closed the connection"
        try:
            while not self._stop.is_set():
                ready, _, _ = select.select([sock], [], [], 0.2)
                if not ready:
                    continue
                chunk = sock.recv(65536)
                if not chunk:
                    if buffer.strip():
                        reason += f" in the middle of a line ({len(buffer)} bytes unterminated)"
                    break
                buffer.extend(chunk)
                while True:
                    cuts = [i for i in (buffer.find(b"\n"), buffer.find(b"\r")) if i >= 0]
                    if not cuts:
                        break
                    raw = bytes(buffer[: min(cuts)])
                    del buffer[: min(cuts) + 1]
                    if raw.strip():
                        self._dispatch(raw.decode("utf-8", "replace"))
                if len(buffer) > MAX_LINE_BYTES:
                    log.warning("server sent a line longer than %d bytes; discarded",
                                MAX_LINE_BYTES)
                    buffer.clear()
        except (OSError, ValueError) as exc:
            if not self._stop.is_set():
                reason = f"connection error: {exc}"
        self._set_closed(reason)

    def _set_closed(self, reason: str) -> None:
        with self._cond:
            if self._closed_reason is None:
                self._closed_reason = reason
                if not self._stop.is_set():
                    log.warning("%s:%d: %s", self.host, self.port, reason)
            self._cond.notify_all()
        self._replies.put(None)

    def _dispatch(self, line: str) -> None:
        wire_log.debug("<- %s", line)
        try:
            msg = parse_line(line)
        except ProtocolError as exc:
            log.warning("ignoring a malformed line from the server: %s", exc)
            return
        rec = Received(line, msg, time.monotonic())
        if isinstance(msg, m.GameInfo) and self.game_info is None:
            with self._cond:
                self.game_info = msg
                self._cond.notify_all()
            return
        if isinstance(msg, _STREAMS):
            self._on_stream(rec, msg)
            return
        if isinstance(msg, (m.StartPoses, m.Conf, m.PlatformConf, m.Geo)):
            self._replies.put(rec)
            return
        log.debug("unsolicited %s line: %s", type(msg).__name__, line)
        for sub in list(self._subscribers):
            sub(rec)

    def _on_stream(self, rec: Received, msg: m.Asta | m.Sta | m.Sen | m.Eff) -> None:
        if isinstance(msg, m.Asta):
            key, component = ("ASTA", msg.name), f"Actuator {msg.name}"
        elif isinstance(msg, m.Sta):
            key, component = ("STA", ""), ""
        else:
            key, component = (type(msg).__name__.upper(), msg.name), f"{msg.type} {msg.name}"
        with self._cond:
            self._latest[key] = rec
            if component:
                self._components.setdefault(component)
            self._stream_count += 1
            if self._first_status is None:
                self._first_status = rec
            self._cond.notify_all()
        for sub in list(self._subscribers):
            try:
                sub(rec)
            except Exception:
                log.exception("a subscriber failed on %s", rec.line)

    # ------------------------------------------------------------------ streams
    def subscribe(self, callback: Subscriber) -> Callable[[], None]:
        """Call ``callback`` (on the reader thread) for every unsolicited line; returns an
        unsubscribe function. Callbacks must be quick."""
        self._subscribers.append(callback)
        return lambda: self._subscribers.remove(callback) if callback in self._subscribers \
            else None

    def latest_asta(self, actuator: str) -> m.Asta | None:
        """The most recent ASTA of ``actuator``, if any arrived."""
        rec = self._latest.get(("ASTA", actuator))
        return rec.message if rec else None  # type: ignore[return-value]

    def latest_sen(self, sensor: str) -> m.Sen | None:
        """The most recent SEN of ``sensor``, if any arrived."""
        rec = self._latest.get(("SEN", sensor))
        return rec.message if rec else None  # type: ignore[return-value]

    def latest_line(self, kind: str, name: str) -> str | None:
        """The raw text of the latest ``kind`` (ASTA, SEN, EFF) line of component ``name``."""
        rec = self._latest.get((kind, name))
        return rec.line if rec else None

    def wait_asta(self, actuator: str, after_time: float | None = None,
                  timeout: float | None = None) -> m.Asta:
        """Wait for an ASTA of ``actuator`` with simulated time > ``after_time``."""
        return self._wait_stream(("ASTA", actuator), after_time, timeout,
                                 f"ASTA from actuator {actuator}")  # type: ignore[return-value]

    def wait_sen(self, sensor: str, after_time: float | None = None,
                 timeout: float | None = None) -> m.Sen:
        """Wait for a SEN of ``sensor`` with simulated time > ``after_time``."""
        return self._wait_stream(("SEN", sensor), after_time, timeout,
                                 f"SEN from sensor {sensor}")  # type: ignore[return-value]

    def _wait_stream(self, key: tuple[str, str], after: float | None, timeout: float | None,
                     what: str) -> m.Message:
        limit = self.timeout if timeout is None else timeout

        def ready() -> bool:
            rec = self._latest.get(key)
            if rec is None:
                return False
            t = getattr(rec.message, "time", None)
            return after is None or (t is not None and t > after)

        with self._cond:
            ok = self._cond.wait_for(lambda: ready() or self._closed_reason is not None, limit)
            if ready():
                return self._latest[key].message
        if not ok:
            raise ResponseTimeoutError(what, limit, "known components: "
                                       + (", ".join(self._components) or "(none yet)"))
        raise ConnectionLostError(f"waiting for {what}", self._closed_reason or "")

    def known_components(self) -> list[str]:
        """``Type Name`` of every component seen in the streams or replies so far."""
        return list(self._components)

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
        with self._request_lock:
            while True:  # discard replies that arrived late for an earlier request
                try:
                    stale = self._replies.get_nowait()
                except queue.Empty:
                    break
                if stale is not None:
                    log.debug("discarding a late reply: %s", stale.line)
            self.send(msg)
            deadline = time.monotonic() + limit
            while True:
                remaining = deadline - time.monotonic()
                if self._closed_reason is not None:
                    raise ConnectionLostError(f"waiting for the reply to `{what}`",
                                              self._closed_reason)
                try:
                    rec = self._replies.get(timeout=max(0.0, remaining))
                except queue.Empty:
                    if isinstance(msg, (m.GetConf, m.GetGeo)):
                        raise UnknownComponentError(what, limit, self.known_components()) from None
                    raise ResponseTimeoutError(f"reply to `{what}`", limit) from None
                if rec is None:
                    continue  # woken by a close; re-checked above
                if accept(rec.message):
                    self._note_components(rec.message)
                    return rec
                log.debug("discarding a reply that does not answer `%s`: %s", what, rec.line)

    def _note_components(self, msg: m.Message) -> None:
        if isinstance(msg, (m.Conf, m.Geo)) and msg.type.lower() in ("actuator", "groundtruth"):
            kind = "Actuator" if msg.type.lower() == "actuator" else "GroundTruth"
            with self._cond:
                for item in msg.items:
                    self._components.setdefault(f"{kind} {item.name}")

    def get_start_poses(self, timeout: float | None = None) -> m.StartPoses:
        """``GETSTARTPOSES``: the named spawn poses the server offers."""
        rec = self.request(m.GetStartPoses(), lambda x: isinstance(x, m.StartPoses), timeout)
        return rec.message  # type: ignore[return-value]

    def get_conf(self, type_: str, name: str | None = None, timeout: float | None = None
                 ) -> m.Conf | m.PlatformConf:
        """``GETCONF {Type T} [{Name n}]``; Type ``Robot`` gives the platform's CONF."""
        rec = self.request(m.GetConf(type_, name), _conf_matcher(type_, name), timeout)
        return rec.message  # type: ignore[return-value]

    def get_geo(self, type_: str, name: str | None = None, timeout: float | None = None
                ) -> m.Geo:
        """``GETGEO {Type T} [{Name n}]``."""
        rec = self.request(m.GetGeo(type_, name), _geo_matcher(type_, name), timeout)
        return rec.message  # type: ignore[return-value]

    def init(self, class_name: str, name: str | None = None, start: str | None = None,
             location: m.Vector3 | None = None, rotation: m.Vector3 | None = None) -> None:
        """Send ``INIT`` (no reply comes; see :meth:`spawn`)."""
        with self._cond:
            self._first_status = None
        self.send(m.Init(class_name, name, start, location, rotation))

    def spawn(self, class_name: str, name: str | None = None, start: str | None = None,
              location: m.Vector3 | None = None, rotation: m.Vector3 | None = None,
              timeout: float | None = None, known_classes: Sequence[str] = ()) -> Received:
        """INIT a robot and wait until its first status line shows it exists.

        Raises:
            UnknownRobotError: nothing appeared within the timeout (the usual cause is a class
                the server does not know; UDK says nothing either way).
        """
        limit = self.timeout if timeout is None else timeout
        self.init(class_name, name, start, location, rotation)
        with self._cond:
            self._cond.wait_for(lambda: self._first_status is not None
                                or self._closed_reason is not None, limit)
            first = self._first_status
        if first is None:
            if self._closed_reason is not None:
                raise ConnectionLostError(f"waiting for {class_name} to spawn",
                                          self._closed_reason)
            raise UnknownRobotError(class_name, known_classes,
                                    f"no status line within {limit:g} s of INIT; USARSim does "
                                    "not reply to INIT, so an unknown class and a failed spawn "
                                    "look the same")
        return first

    def act(self, actuator: str, targets: Sequence[float] | Mapping[int, float]) -> None:
        """``ACT``: joint targets (rad or m). A sequence sets links 0..n-1; a mapping sets the
        given 0-based links only."""
        pairs = (tuple(sorted(targets.items())) if isinstance(targets, Mapping)
                 else tuple(enumerate(float(v) for v in targets)))
        self.send(m.Act(actuator, tuple((int(k), float(v)) for k, v in pairs)))


def _conf_matcher(type_: str, name: str | None) -> Callable[[m.Message], bool]:
    def accept(msg: m.Message) -> bool:
        if type_ == "Robot":
            return isinstance(msg, m.PlatformConf) and (
                not name or msg.name.upper() == name.upper())
        return (isinstance(msg, m.Conf) and msg.type.lower() == type_.lower()
                and (not name or any(i.name.upper() == name.upper() for i in msg.items)))
    return accept


def _geo_matcher(type_: str, name: str | None) -> Callable[[m.Message], bool]:
    def accept(msg: m.Message) -> bool:
        if not isinstance(msg, m.Geo):
            return False
        if type_ == "Robot":
            return msg.type.lower() not in ("actuator", "groundtruth") and (
                not name or any(i.name.upper() == name.upper() for i in msg.items))
        return msg.type.lower() == type_.lower() and (
            not name or any(i.name.upper() == name.upper() for i in msg.items))
    return accept
