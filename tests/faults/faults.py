"""The faults a USARSim server can commit, as scripts for :class:`~tests.faults.proxy.FaultProxy`.

Discovery faults strike while the client learns the robot (GETCONF/GETGEO); motion faults strike
0.3 s into a real motion (after the drive identification).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable

from tests.faults.proxy import Close, Fault, Link, Op, Slow, Stall, head

TEN_MB = 10 * 1024 * 1024
GARBAGE = bytes(range(256)).replace(b"\n", b"").replace(b"\r", b"") * 2 + b"\r\n"
"""Every byte value but CR/LF (control characters, invalid UTF-8), twice, then CRLF."""
MOTION_DELAY_S = 0.3


def _is_actuator_reply(line: bytes, kind: str) -> bool:
    return head(line) == kind and b"{Type Actuator}" in line


def _long_line(prefix: bytes) -> list[Op]:
    chunk = b"x" * 65536
    return [prefix, *([chunk] * (TEN_MB // len(chunk))), Stall()]


class Silent(Fault):
    """Accepts the connection and never says anything."""

    name = "silent"
    connect_upstream = False


class NfoThenNothing(Fault):
    """Greets (NFO), then never sends another byte."""

    name = "nfo-then-nothing"

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        link.fault()
        return [line, Stall()]


class NoConfGeo(Fault):
    """Never answers GETCONF/GETGEO (what UDK does when nothing matches)."""

    name = "no-conf-geo"

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        if head(line) in ("CONF", "GEO"):
            link.fault()
            return []
        return [line]


class CloseMidGeo(Fault):
    """Closes the connection halfway through the actuator's GEO line."""

    name = "close-mid-geo"

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        if _is_actuator_reply(line, "GEO"):
            link.fault()
            return [line[: len(line) // 2], Close()]
        return [line]


class LongLine(Fault):
    """Answers the actuator's GETCONF with 10 MB and no line end, then nothing."""

    name = "10mb-line"

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        if _is_actuator_reply(line, "CONF"):
            link.fault()
            return _long_line(b"CONF {Type Actuator} {Name ")
        return [line]


class Garbage(Fault):
    """Answers the actuator's GETCONF with a line of binary garbage."""

    name = "garbage"

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        if _is_actuator_reply(line, "CONF"):
            link.fault()
            return [GARBAGE]
        return [line]


class InvalidUtf8(Fault):
    """The actuator's CONF arrives with bytes that are not UTF-8 in the actuator name."""

    name = "invalid-utf8"

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        if _is_actuator_reply(line, "CONF"):
            link.fault()
            return [line.replace(b"{Name KR60Arm}", b"{Name KR60\xff\xfeArm}", 1)]
        return [line]


class Rewrite(Fault):
    """Rewrites the actuator's CONF or GEO reply with ``edit`` (a regex substitution)."""

    def __init__(self, name: str, kind: str, pattern: str, replacement: str):
        self.name = name
        self.kind = kind
        self.pattern = re.compile(pattern.encode())
        self.replacement = replacement.encode()

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        if _is_actuator_reply(line, self.kind):
            new, n = self.pattern.subn(self.replacement, line, count=1)
            assert n == 1, f"{self.name}: pattern not found in {line[:200]!r}"
            link.fault()
            return [new]
        return [line]


class SlowServer(Fault):
    """Sends every byte 100 ms after the previous one, from the greeting on."""

    name = "slow"

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        link.fault()
        return [Slow(line, 0.1)]


# ------------------------------------------------------------------------------ motion faults


class _InMotion(Fault):
    """Forwards everything until ``MOTION_DELAY_S`` into a real motion, then ``strike``."""

    def server_line(self, link: Link, line: bytes) -> Iterable[Op]:
        if link.in_motion(MOTION_DELAY_S):
            return self.strike(link, line)
        return [line]

    def strike(self, link: Link, line: bytes) -> Iterable[Op]:
        raise NotImplementedError


class AstaStops(_InMotion):
    """Stops sending ASTA mid-motion (everything else keeps coming)."""

    name = "asta-stops"

    def strike(self, link: Link, line: bytes) -> Iterable[Op]:
        if head(line) == "ASTA":
            link.fault()
            return []
        return [line]


class SlowMidMotion(_InMotion):
    """Sends every byte 100 ms after the previous one, from mid-motion on."""

    name = "slow-mid-motion"

    def strike(self, link: Link, line: bytes) -> Iterable[Op]:
        link.fault()
        return [Slow(line, 0.1)]


class CloseMidMotion(_InMotion):
    """Closes the connection mid-motion."""

    name = "close-mid-motion"

    def strike(self, link: Link, line: bytes) -> Iterable[Op]:
        link.fault()
        return [Close()]


class GarbageMidMotion(_InMotion):
    """One line of binary garbage mid-motion; everything else keeps coming."""

    name = "garbage-mid-motion"

    def strike(self, link: Link, line: bytes) -> Iterable[Op]:
        if link.fault_at is None:
            link.fault()
            return [GARBAGE, line]
        return [line]


class LongLineMidMotion(_InMotion):
    """10 MB without a line end mid-motion, then nothing."""

    name = "10mb-line-mid-motion"

    def strike(self, link: Link, line: bytes) -> Iterable[Op]:
        link.fault()
        return _long_line(b"ASTA {Time ")


class NanAsta(_InMotion):
    """ASTA values turn to NaN mid-motion."""

    name = "nan-asta"

    def strike(self, link: Link, line: bytes) -> Iterable[Op]:
        if head(line) == "ASTA":
            link.fault()
            return [re.sub(rb"\{Value [^}]*\}", b"{Value nan}", line)]
        return [line]


Factory = Callable[[], Fault]
