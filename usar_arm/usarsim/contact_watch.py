"""Every contact a robot's reports name while a watch is open (the contact extension: each
report holds the contacts since the one before it, so a reader that only looked at the latest
would lose those of the reports it missed)."""

from __future__ import annotations

import threading
from collections.abc import Callable

from usar_arm.usarsim import messages as m
from usar_arm.usarsim.inbox import Received


class ContactWatch:
    """Collects the contact reports of robot ``robot`` (its INIT name) from a client's stream.

    Args:
        subscribe: the client's ``subscribe`` (any :class:`~.exchange.Exchange`).
        robot: the robot's name. Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, subscribe: Callable[[Callable[[Received], None]], Callable[[], None]],
                 robot: str):
        self.robot = robot
        self._lock = threading.Lock()
        self._pairs: list[m.ContactPair] = []
        self.reports = 0
        """Reports seen."""
        self.last_time: float | None = None
        """Simulated time (s) of the latest report: no contact until then is missing."""
        self._unsubscribe = subscribe(self._on_line)

    def _on_line(self, rec: Received) -> None:
        msg = rec.message
        if isinstance(msg, m.ContactReport) and msg.name == self.robot:
            with self._lock:
                self._pairs.extend(msg.pairs)
                self.reports += 1
                self.last_time = msg.time

    def pairs(self) -> tuple[m.ContactPair, ...]:
        """Every contact reported so far, in report order."""
        with self._lock:
            return tuple(self._pairs)

    def deepest(self) -> float:
        """The deepest penetration (m) reported so far (0 for none)."""
        return max((p.depth for p in self.pairs()), default=0.0)

    def close(self) -> None:
        """Stop collecting."""
        self._unsubscribe()

    def __enter__(self) -> ContactWatch:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
