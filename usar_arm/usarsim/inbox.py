"""Where the lines a USARSim server sends go: parsed, then routed.

Replies (CONF, GEO, start poses) queue for the request waiting for one; unsolicited status (ASTA,
STA, SEN, EFF) updates per-component caches that waiters and subscribers read; the NFO greeting is
kept. A line that is not USARSim is logged and counted, so a waiter can fail on it at once.
Each :class:`Received` carries the line's printed precision as data (:attr:`Received.steps`).
"""

from __future__ import annotations

import logging
import queue
import re
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from usar_arm.core.errors import ProtocolError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import parse_line
from usar_arm.usarsim.lines import BadLine
from usar_arm.usarsim.numbers import printed_steps

log = logging.getLogger("usar_arm.usarsim")
wire_log = logging.getLogger("usar_arm.usarsim.wire")

STATUS_HEADS = frozenset({"ASTA", "STA", "SEN", "EFF", "MISSTA"})
"""Command words of the unsolicited status lines: a malformed one does not fail a request."""
_SENSOR_LINES = (m.Sen, m.RangeScan, m.Ins, m.Odometry, m.ContactReport, m.GripTruth)
"""Every SEN line (the typed ones too): cached under ``("SEN", name)``."""
_STREAMS = (m.Asta, m.Sta, m.Eff, *_SENSOR_LINES)
_REPLIES = (m.StartPoses, m.Conf, m.PlatformConf, m.Geo, m.WcStatus)
_COMMAND_WORD = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
_WARN_BAD_LINES = 5
"""Malformed lines logged as warnings per connection; the rest at DEBUG (a flood stays short)."""
_KEEP_BAD_LINES = 100


@dataclass(frozen=True)
class Received:
    """A line received from the server: its text (no terminator), the message, when it arrived
    (monotonic s), and the step each block's numbers were printed with (lower-case block key ->
    10^-decimals; 0.0 = full precision; see :func:`~usar_arm.usarsim.numbers.printed_steps`)."""

    line: str
    message: m.Message
    wall_time: float
    steps: Mapping[str, float]

    def step(self, key: str) -> float:
        """The printed step of the numbers in this line's ``{key ...}`` blocks (m, rad or s as
        the key's unit; 0.0 for full precision or when the line has no such block)."""
        return self.steps.get(key.lower(), 0.0)


Subscriber = Callable[[Received], None]


class Inbox:
    """Routes parsed lines; every change is made under ``cond`` and notifies it.

    Readers and waiters hold ``cond`` (re-entrant) while they look at the caches.
    """

    def __init__(self, cond: threading.Condition, peer: str):
        self.cond = cond
        self.peer = peer
        self.game_info: m.GameInfo | None = None
        self.bad_lines: list[BadLine] = []
        """Lines from the server that were not USARSim (the latest 100), oldest first."""
        self.bad_line_count = 0
        """How many such lines arrived in all."""
        self.replies: queue.Queue[Received | None] = queue.Queue()
        """Replies in arrival order; None wakes a waiting request (close, bad line)."""
        self.first_status: Received | None = None
        """The first status line since the last :meth:`expect_spawn`."""
        self._latest: dict[tuple[str, str], Received] = {}
        self._components: dict[str, None] = {}
        self._subscribers: list[Subscriber] = []

    # ------------------------------------------------------------------ routing
    def deliver(self, line: str) -> None:
        """Parse one line and route it (called on the reader thread)."""
        wire_log.debug("<- %s", line)
        arrived = time.monotonic()  # the line is whole: its arrival, before any parsing
        word = line.split("{", 1)[0].strip()
        try:
            msg = parse_line(line)
            if isinstance(msg, m.Unknown) and not _COMMAND_WORD.fullmatch(msg.head):
                raise ProtocolError(line, 0, "expected a command word (letters, such as ASTA or "
                                             "CONF) at the start of the line")
        except ProtocolError as exc:
            self.reject(BadLine(word.upper() if _COMMAND_WORD.fullmatch(word) else "", exc))
            return
        rec = Received(line, msg, arrived, printed_steps(line))
        if isinstance(msg, m.GameInfo) and self.game_info is None:
            with self.cond:
                self.game_info = msg
                self.cond.notify_all()
        elif isinstance(msg, _STREAMS):
            self._on_stream(rec, msg)
        elif isinstance(msg, _REPLIES):
            self.replies.put(rec)
        else:
            log.debug("unsolicited %s line: %s", type(msg).__name__, line)
            self._notify(rec)

    def reject(self, bad: BadLine) -> None:
        """Record a line that is not USARSim and wake whatever waits."""
        with self.cond:
            self.bad_lines = [*self.bad_lines[-(_KEEP_BAD_LINES - 1):], bad]
            self.bad_line_count += 1
            count = self.bad_line_count
            self.cond.notify_all()
        self.replies.put(None)  # wakes a request, which then looks at bad_lines
        # A status line is skipped (warn); any other fails what waits for it, which reports it.
        level = logging.WARNING if bad.head in STATUS_HEADS else logging.INFO
        if count > _WARN_BAD_LINES:
            level = logging.DEBUG
        log.log(level, "%s sent a line that is not USARSim%s: %s", self.peer,
                " (further ones are logged at DEBUG)" if count == _WARN_BAD_LINES else "",
                bad.error)

    def wake(self) -> None:
        """Wake a waiting request (the connection closed)."""
        self.replies.put(None)

    def _on_stream(self, rec: Received,
                   msg: m.Asta | m.Sta | m.Sen | m.Eff | m.RangeScan | m.Ins | m.Odometry
                   | m.ContactReport | m.GripTruth) -> None:
        if isinstance(msg, m.Asta):
            key, component = ("ASTA", msg.name), f"Actuator {msg.name}"
        elif isinstance(msg, m.Sta):
            key, component = ("STA", ""), ""
        elif isinstance(msg, _SENSOR_LINES):
            key, component = ("SEN", msg.name), f"{msg.type} {msg.name}"
        else:
            key, component = (type(msg).__name__.upper(), msg.name), f"{msg.type} {msg.name}"
        with self.cond:
            self._latest[key] = rec
            if component:
                self._components.setdefault(component)
            if self.first_status is None:
                self.first_status = rec
            self.cond.notify_all()
        self._notify(rec)

    def _notify(self, rec: Received) -> None:
        for sub in list(self._subscribers):
            try:
                sub(rec)
            except Exception:
                log.exception("a subscriber failed on %s", rec.line)

    # ------------------------------------------------------------------ reading
    def subscribe(self, callback: Subscriber) -> Callable[[], None]:
        """Call ``callback`` (on the reader thread) for every unsolicited line; returns an
        unsubscribe function. Callbacks must be quick."""
        self._subscribers.append(callback)

        def unsubscribe() -> None:
            if callback in self._subscribers:
                self._subscribers.remove(callback)
        return unsubscribe

    def latest(self, kind: str, name: str) -> Received | None:
        """The latest ``kind`` (ASTA, SEN, EFF; STA with name '') line of component ``name``."""
        return self._latest.get((kind, name))

    def newer(self, key: tuple[str, str], after: float | None) -> Received | None:
        """The latest line under ``key`` if its simulated time is after ``after`` (any, when
        ``after`` is None)."""
        rec = self._latest.get(key)
        if rec is None:
            return None
        t = getattr(rec.message, "time", None)
        return rec if after is None or (t is not None and t > after) else None

    def expect_spawn(self) -> None:
        """Forget the first status line, so the next one shows a new robot exists."""
        with self.cond:
            self.first_status = None

    def note_components(self, msg: m.Message) -> None:
        """Remember the actuators and sensors a CONF or GEO reply names."""
        if isinstance(msg, (m.Conf, m.Geo)) and msg.type.lower() in ("actuator", "groundtruth"):
            kind = "Actuator" if msg.type.lower() == "actuator" else "GroundTruth"
            with self.cond:
                for item in msg.items:
                    self._components.setdefault(f"{kind} {item.name}")

    def known_components(self) -> list[str]:
        """``Type Name`` of every component seen in the streams or replies so far."""
        return list(self._components)

    def bad_since(self, count: int, fatal: Callable[[str], bool]) -> BadLine | None:
        """The first line that was not USARSim, of those after the first ``count``, whose
        command word makes ``fatal`` true."""
        with self.cond:  # re-entrant: also called from wait_for predicates
            new = self.bad_line_count - count
            recent = self.bad_lines[-new:] if new > 0 else []
        return next((bad for bad in recent if fatal(bad.head)), None)

    def drop_stale_replies(self) -> None:
        """Discard replies that arrived late for an earlier request."""
        while True:
            try:
                stale = self.replies.get_nowait()
            except queue.Empty:
                return
            if stale is not None:
                log.debug("discarding a late reply: %s", stale.line)
