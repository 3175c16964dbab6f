"""A TCP client for USARSim (UDK) servers: requests with timeouts, streams, robot commands.

Three parts, one concern each: :class:`~usar_arm.usarsim.transport.LineTransport` owns the socket
and the reader thread and frames bytes into lines (CR, LF or CRLF; partial reads and several
lines per read are fine); :class:`~usar_arm.usarsim.inbox.Inbox` parses each line and routes it:
replies (CONF, GEO, start poses) to the request waiting for one, unsolicited status (ASTA, STA,
SEN, EFF) to per-component caches and subscribers; :class:`UsarClient` (here) sends requests one
at a time, as NIST's RosSim did, waits with a timeout and turns silences into errors.

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

import logging
import time
from collections.abc import Callable, Mapping, Sequence

from usar_arm.core.errors import ConnectionLostError, ResponseTimeoutError, UnknownRobotError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.exchange import DEFAULT_TIMEOUT_S, Exchange, in_context
from usar_arm.usarsim.inbox import STATUS_HEADS, Received, Subscriber
from usar_arm.usarsim.lines import BadLine, LineSplitter, decode_line

__all__ = ["DEFAULT_TIMEOUT_S", "STATUS_HEADS", "BadLine", "LineSplitter", "Received",
           "Subscriber", "UsarClient", "decode_line"]

log = logging.getLogger("usar_arm.usarsim")


class UsarClient(Exchange):
    """A connection to one USARSim server (one robot per connection).

    Args:
        host, port: the server (UDK default port 3000).
        timeout: default seconds to wait for any reply.
        connect_timeout: seconds to wait for the TCP connection and the NFO greeting (default:
            ``timeout``).

    Use as a context manager, or call :meth:`connect` and :meth:`close`.
    """

    # ------------------------------------------------------------------ connection
    def connect(self) -> m.GameInfo:
        """Open the connection and wait for the server's NFO greeting."""
        self._wire.open(self.connect_timeout)
        inbox = self._inbox
        with self._cond:
            ok = self._cond.wait_for(lambda: inbox.game_info is not None
                                     or self._wire.closed_reason is not None
                                     or inbox.bad_line_count > 0, self.connect_timeout)
        info = inbox.game_info
        if info is None:
            self.close()
            if inbox.bad_lines:
                raise in_context(inbox.bad_lines[0].error, f"{self.host}:{self.port} accepted "
                                  "the connection, but instead of the NFO greeting it sent a "
                                  "line that is not USARSim")
            if not ok:
                said = (self._wire.slow_hint(0) or "sent lines, but no NFO greeting"
                        if self.bytes_received else "has sent nothing")
                raise ResponseTimeoutError(
                    "NFO greeting", self.connect_timeout,
                    f"{self.host}:{self.port} accepted the connection but {said} (a USARSim "
                    "server greets every connection at once)")
            raise ConnectionLostError("waiting for the NFO greeting", self.closed_reason or "")
        log.info("connected to %s:%d (%s, %s)", self.host, self.port, info.gametype, info.level)
        return info

    def close(self) -> None:
        """Close the connection (the server then destroys this connection's robot)."""
        self._wire.close()

    def __enter__(self) -> UsarClient:
        if self._wire.local_port is None:
            self.connect()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ robot commands
    def get_start_poses(self, timeout: float | None = None) -> m.StartPoses:
        """``GETSTARTPOSES``: the named spawn poses the server offers."""
        rec = self.request(m.GetStartPoses(), lambda x: isinstance(x, m.StartPoses), timeout)
        assert isinstance(rec.message, m.StartPoses), "accepted only start poses"
        return rec.message

    def get_conf(self, type_: str, name: str | None = None, timeout: float | None = None
                 ) -> m.Conf | m.PlatformConf:
        """``GETCONF {Type T} [{Name n}]``; Type ``Robot`` gives the platform's CONF."""
        rec = self.request(m.GetConf(type_, name), _conf_matcher(type_, name), timeout)
        assert isinstance(rec.message, (m.Conf, m.PlatformConf)), "accepted only a CONF"
        return rec.message

    def get_geo(self, type_: str, name: str | None = None, timeout: float | None = None
                ) -> m.Geo:
        """``GETGEO {Type T} [{Name n}]``."""
        rec = self.request(m.GetGeo(type_, name), _geo_matcher(type_, name), timeout)
        assert isinstance(rec.message, m.Geo), "accepted only a GEO"
        return rec.message

    def init(self, class_name: str, name: str | None = None, start: str | None = None,
             location: m.Vector3 | None = None, rotation: m.Vector3 | None = None) -> None:
        """Send ``INIT`` (no reply comes; see :meth:`spawn`)."""
        self._inbox.expect_spawn()
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
        inbox = self._inbox
        count, received = inbox.bad_line_count, self.bytes_received
        self.init(class_name, name, start, location, rotation)
        with self._cond:
            self._cond.wait_for(lambda: inbox.first_status is not None
                                or self.closed_reason is not None
                                or inbox.bad_since(count, lambda h: h not in STATUS_HEADS)
                                is not None, limit)
            first = inbox.first_status
            bad = inbox.bad_since(count, lambda head: True)
        if first is None:
            if bad is not None:
                raise in_context(bad.error, f"after INIT of {class_name}, the server sent a "
                                             "line that is not USARSim")
            if self.closed_reason is not None:
                raise ConnectionLostError(f"waiting for {class_name} to spawn",
                                          self.closed_reason)
            slow = self._wire.slow_hint(received)
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


    # ------------------------------------------------------------------ effectors
    def set_effector(self, type_: str, name: str, opcode: str, params: str | None = None
                     ) -> None:
        """``SET {Type T} {Name n} {Opcode op} [{Params p}]`` (``Gripper`` or ``ToolChanger``;
        OPEN, CLOSE, GRIP). UDK never answers: read the effect with :meth:`wait_effector`."""
        self.send(m.Set(type_, name, opcode, params))

    def latest_eff(self, name: str) -> m.Eff | None:
        """The most recent EFF of effector ``name``, if any arrived."""
        rec = self._inbox.latest("EFF", name)
        return rec.message if rec is not None and isinstance(rec.message, m.Eff) else None

    def wait_effector(self, name: str, status: str | None = None,
                      after_time: float | None = None, timeout: float | None = None) -> m.Eff:
        """Wait for an EFF of ``name`` later than ``after_time`` (s of simulated time) whose
        Status is ``status`` (any, when None).

        Raises:
            ResponseTimeoutError: none came within the timeout (names the last status seen).
        """
        limit = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + limit
        last: m.Eff | None = None
        while True:
            try:
                rec = self.wait_stream("EFF", name, after_time,
                                       max(0.0, deadline - time.monotonic()))
            except ResponseTimeoutError:
                if last is None:
                    raise
                raise ResponseTimeoutError(f"EFF of {name} with Status {status}", limit,
                                           f"its last EFF said {last.status}") from None
            eff = rec.message
            assert isinstance(eff, m.Eff), "the EFF cache holds EFF lines"
            if status is None or eff.status == status.upper():
                return eff
            last, after_time = eff, eff.time

    def latest_grip(self, name: str) -> m.GripTruth | None:
        """The most recent GripTruth (the extension) of vacuum ``name``: what it holds."""
        rec = self._inbox.latest("SEN", name)
        return (rec.message if rec is not None and isinstance(rec.message, m.GripTruth)
                else None)

    def wait_grip(self, name: str, after_time: float | None = None,
                  timeout: float | None = None) -> m.GripTruth:
        """Wait for a GripTruth of vacuum ``name`` later than ``after_time``."""
        msg = self.wait_stream("SEN", name, after_time, timeout).message
        if not isinstance(msg, m.GripTruth):
            raise ResponseTimeoutError(f"GripTruth of {name}", self.timeout if timeout is None
                                       else timeout, f"{name} sends SEN lines of another type")
        return msg

    def latest_contacts(self, robot: str) -> m.ContactReport | None:
        """The most recent contact report (the extension) of robot ``robot`` (its INIT name):
        the contacts since the report before it (:class:`~.contact_watch.ContactWatch`
        keeps every report)."""
        rec = self._inbox.latest("SEN", robot)
        return (rec.message if rec is not None and isinstance(rec.message, m.ContactReport)
                else None)


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
