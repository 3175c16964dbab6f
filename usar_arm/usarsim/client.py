"""A TCP client for USARSim (UDK) servers: line framing, requests with timeouts, streams.

A background thread reads the socket, splits lines at any of CR, LF or CRLF (partial reads and
several lines per read are fine), parses them and routes them: replies (NFO, CONF, GEO) to the
request waiting for one, unsolicited status (ASTA, STA, SEN, EFF) to per-component caches and to
subscribers. Every wait has a timeout. Requests are sent one at a time, as NIST's RosSim did.

UDK sends **no reply** to a GETCONF/GETGEO that matches nothing, and none to INIT; the client turns
those silences into errors that name what the server does know, or, when bytes did arrive but no
complete line, that say the server is answering too slowly.

A line that is not USARSim (not UTF-8 text, control characters, a grammar error, a number that is
not finite, longer than :data:`~usar_arm.usarsim.codec.MAX_LINE_BYTES` without a line end) is
counted and logged, and fails at once whatever waits for that kind of line: a request fails on any
such line that is not a status line (ASTA, STA, SEN, EFF), a wait for ASTA on one that is ASTA or
unrecognisable. The rest of an overlong line is skipped up to its line end, so memory stays
bounded whatever the server sends.
"""

from __future__ import annotations

import contextlib
import logging
import queue
import re
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
    UsarArmError,
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
STATUS_HEADS = frozenset({"ASTA", "STA", "SEN", "EFF", "MISSTA"})
"""Command words of the unsolicited status lines: a malformed one does not fail a request."""
_COMMAND_WORD = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
_WARN_BAD_LINES = 5
"""Malformed lines logged as warnings per connection; the rest at DEBUG (a flood stays short)."""


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


class UsarClient:
    """A connection to one USARSim server (one robot per connection).

    Args:
        host, port: the server (UDK default port 3000).
        timeout: default seconds to wait for any reply.
        connect_timeout: seconds to wait for the TCP connection and the NFO greeting (default:
            ``timeout``).

    Use as a context manager, or call :meth:`connect` and :meth:`close`.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 3000,
                 timeout: float = DEFAULT_TIMEOUT_S, connect_timeout: float | None = None):
        self.host = host
        self.port = port
        self.timeout = timeout
        self.connect_timeout = timeout if connect_timeout is None else connect_timeout
        self.game_info: m.GameInfo | None = None
        self.bad_lines: list[BadLine] = []
        """Lines from the server that were not USARSim (the latest 100), oldest first."""
        self.bad_line_count = 0
        """How many such lines arrived in all."""
        self.bytes_received = 0
        """Bytes received in all."""
        self._splitter = LineSplitter()
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
            ok = self._cond.wait_for(lambda: self.game_info is not None or self._closed_reason
                                     or self.bad_line_count > 0, self.connect_timeout)
        if self.game_info is None:
            self.close()
            if self.bad_lines:
                raise _in_context(self.bad_lines[0].error, f"{self.host}:{self.port} accepted the "
                                  "connection, but instead of the NFO greeting it sent a line "
                                  "that is not USARSim")
            if not ok:
                said = (self._slow_hint(0) or "sent lines, but no NFO greeting"
                        if self.bytes_received else "has sent nothing")
                raise ResponseTimeoutError(
                    "NFO greeting", self.connect_timeout,
                    f"{self.host}:{self.port} accepted the connection but {said} (a USARSim "
                    "server greets every connection at once)")
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

    @property
    def closed_reason(self) -> str | None:
        """Why the connection closed (None while it is open)."""
        return self._closed_reason

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
                    if self._splitter.buffer.strip():
                        reason += (f" in the middle of a line ({self._splitter.partial} bytes "
                                   "unterminated)")
                    break
                with self._cond:
                    self.bytes_received += len(chunk)
                for item in self._splitter.feed(chunk):
                    if isinstance(item, BadLine):
                        self._bad_line(item)
                        continue
                    try:
                        text = decode_line(item)
                    except ProtocolError as exc:
                        self._bad_line(BadLine("", exc))
                        continue
                    self._dispatch(text)
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

    def _bad_line(self, bad: BadLine) -> None:
        with self._cond:
            self.bad_lines = [*self.bad_lines[-99:], bad]
            self.bad_line_count += 1
            count = self.bad_line_count
            self._cond.notify_all()
        self._replies.put(None)  # wakes a request, which then looks at bad_lines
        # A status line is skipped (warn); any other fails what waits for it, which reports it.
        level = logging.WARNING if bad.head in STATUS_HEADS else logging.INFO
        if count > _WARN_BAD_LINES:
            level = logging.DEBUG
        log.log(level, "%s:%d sent a line that is not USARSim%s: %s", self.host, self.port,
                " (further ones are logged at DEBUG)" if count == _WARN_BAD_LINES else "",
                bad.error)

    def _bad_since(self, count: int, fatal: Callable[[str], bool]) -> BadLine | None:
        """The first line that was not USARSim, of those after the first ``count``, whose
        command word makes ``fatal`` true."""
        with self._cond:  # re-entrant: also called from wait_for predicates
            new = self.bad_line_count - count
            recent = self.bad_lines[-new:] if new > 0 else []
        return next((bad for bad in recent if fatal(bad.head)), None)

    def _slow_hint(self, received_before: int) -> str:
        """'is answering too slowly ...' when bytes arrived since ``received_before`` but no
        complete line did; '' otherwise."""
        got = self.bytes_received - received_before
        if got <= 0 or self._splitter.partial == 0:
            return ""
        return (f"is answering too slowly: {got} byte(s) arrived but the line is still "
                f"unfinished ({self._splitter.partial} byte(s) of it so far)")

    def _dispatch(self, line: str) -> None:
        wire_log.debug("<- %s", line)
        word = line.split("{", 1)[0].strip()
        try:
            msg = parse_line(line)
            if isinstance(msg, m.Unknown) and not _COMMAND_WORD.fullmatch(msg.head):
                raise ProtocolError(line, 0, "expected a command word (letters, such as ASTA or "
                                             "CONF) at the start of the line")
        except ProtocolError as exc:
            head = word.upper() if _COMMAND_WORD.fullmatch(word) else ""
            self._bad_line(BadLine(head, exc))
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

        def fatal(head: str) -> bool:
            return head in ("", key[0])

        with self._cond:
            count, received = self.bad_line_count, self.bytes_received
            ok = self._cond.wait_for(lambda: ready() or self._closed_reason is not None
                                     or self._bad_since(count, fatal) is not None, limit)
            if ready():
                return self._latest[key].message
            bad = self._bad_since(count, fatal) or self._bad_since(count, lambda h: True)
        if bad is not None:
            raise _in_context(bad.error, f"while waiting for {what}, the server sent a line "
                                         "that is not USARSim")
        if not ok:
            raise ResponseTimeoutError(what, limit, self._slow_hint(received) or (
                "known components: " + (", ".join(self._components) or "(none yet)")))
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
            count, received = self.bad_line_count, self.bytes_received
            self.send(msg)
            deadline = time.monotonic() + limit
            while True:
                remaining = deadline - time.monotonic()
                bad = self._bad_since(count, lambda head: head not in STATUS_HEADS)
                if bad is not None:
                    raise _in_context(bad.error, f"the reply to `{what}` is not USARSim")
                if self._closed_reason is not None:
                    raise ConnectionLostError(f"waiting for the reply to `{what}`",
                                              self._closed_reason)
                try:
                    rec = self._replies.get(timeout=max(0.0, remaining))
                except queue.Empty:
                    raise self._no_reply(msg, what, limit, count, received) from None
                if rec is None:
                    continue  # woken by a close or a bad line; re-checked above
                if accept(rec.message):
                    self._note_components(rec.message)
                    return rec
                log.debug("discarding a reply that does not answer `%s`: %s", what, rec.line)

    def _no_reply(self, msg: m.Message, what: str, limit: float, count: int, received: int
                  ) -> UsarArmError:
        """The error for a request that got no reply within ``limit`` s."""
        bad = self._bad_since(count, lambda head: True)
        if bad is not None:
            return _in_context(bad.error, f"no reply to `{what}` within {limit:g} s; meanwhile "
                                          "the server sent a line that is not USARSim")
        slow = self._slow_hint(received)
        if slow:
            return ResponseTimeoutError(f"reply to `{what}`", limit, f"the server {slow}")
        if isinstance(msg, (m.GetConf, m.GetGeo)):
            return UnknownComponentError(what, limit, self.known_components())
        return ResponseTimeoutError(f"reply to `{what}`", limit,
                                    "the server has sent nothing at all since the request"
                                    if received == self.bytes_received else "")

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
        count, received = self.bad_line_count, self.bytes_received
        self.init(class_name, name, start, location, rotation)
        with self._cond:
            self._cond.wait_for(lambda: self._first_status is not None
                                or self._closed_reason is not None
                                or self._bad_since(count, lambda h: h not in STATUS_HEADS)
                                is not None, limit)
            first = self._first_status
            bad = self._bad_since(count, lambda head: True)
        if first is None:
            if bad is not None:
                raise _in_context(bad.error, f"after INIT of {class_name}, the server sent a "
                                             "line that is not USARSim")
            if self._closed_reason is not None:
                raise ConnectionLostError(f"waiting for {class_name} to spawn",
                                          self._closed_reason)
            slow = self._slow_hint(received)
            if slow:
                raise ResponseTimeoutError(f"status line of {class_name} after INIT", limit,
                                           f"the server {slow}")
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


def _in_context(error: ProtocolError, context: str) -> ProtocolError:
    """``error`` again, its reason prefixed by what the client was doing."""
    return ProtocolError(error.line, error.position, f"{context}: {error.reason}")


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
