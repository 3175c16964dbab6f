"""Shared machinery of the simulator load, abuse and soak tools (not part of the package).

* :class:`ServerProcess`: ``usar-arm sim`` in its own process, its log in a file, its RSS, thread
  count and CPU time read from ``/proc/<pid>``.
* :class:`Bot`: one well-behaved client on raw asyncio streams. It spawns a robot, streams full
  ``ACT`` lines at a fixed rate on drift-free deadlines (joint 1 follows a slow sine), probes the
  request round trip with ``GETCONF {Type Robot}`` and records every ``ASTA`` (wall and simulated
  time) and the tracking error of joint 1, so that any time window can be summarised afterwards.
* :class:`Driver`: the same for a ground vehicle (P3AT): ``DRIVE`` at up to 20 Hz with slowly
  varying wheel speeds, every ``STA`` and every ``SEN`` by sensor type recorded.
* :class:`Flooder`: one abusive client sending a fixed number of lines per second (valid ACT,
  malformed lines, binary junk or oversized lines).

Wall times are ``time.monotonic()`` seconds; simulated times are the ``{Time t}`` of the server.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import itertools
import json
import math
import os
import re
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from array import array
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

CLK_TCK = os.sysconf("SC_CLK_TCK")
ACTUATOR = "KR60Arm"
ROBOT_CLASS = "USARBot.KR60"
_LISTENING = re.compile(r"listening on [^:\s]+:(\d+)")
_TIME = re.compile(rb"\{Time ([^}]*)\}")
_VALUE = re.compile(rb"\{Value ([^}]*)\}")
_TYPE = re.compile(rb"\{Type ([^}]*)\}")
_LOCATION = re.compile(rb"\{Location ([^}]*)\}")
_RANGE = re.compile(rb"\{Range ([^}]*)\}")
_SCAN_INTERVAL = re.compile(rb"\{ScanInterval ([^}]*)\}")
VEHICLE_CLASS = "USARBot.P3AT"
VEHICLE_MAX_SPEED = 1.2999
"""The P3AT's wheel speed limit (rad/s), as its CONF's MaxSpeed."""
DRIVE_MAX_HZ = 20.0
"""Most DRIVE lines per second a vehicle client sends: a vehicle's controller runs at the rate
of its sensors and status (10 Hz), or twice that (the 20 Hz of a ROS 2 navigation controller),
not at an arm's 100 Hz servo rate."""
SEN_INTERVAL_S = {"GroundTruth": 0.1, "INS": 0.2, "Odometry": 0.1, "RangeScanner": 0.2}
"""ScanInterval (s) of each P3AT sensor type (DefaultUSAR.ini, docs/protocol.md section 9):
what a Driver expects of a sensor whose CONF does not say."""


# ---------------------------------------------------------------------------------- the server


@dataclass(frozen=True)
class ProcSample:
    """One reading of the server process: wall time (s), RSS (KiB), threads, CPU time (s), and
    how long its main thread has waited for a CPU while runnable (s; high on a busy machine)."""

    t: float
    rss_kib: int
    threads: int
    cpu_s: float
    wait_s: float = 0.0


class ServerProcess:
    """``usar-arm sim`` in a child process on a free port, logging to ``log_path``.

    Args:
        log_path: file that receives the server's stderr (its log).
        speed: ``--speed`` of the simulator.
        extra_args: more ``usar-arm sim`` arguments.
        start_timeout: seconds to wait for the "listening on" log line.
    """

    def __init__(self, log_path: Path, speed: float = 1.0, extra_args: tuple[str, ...] = (),
                 start_timeout: float = 60.0):
        self.log_path = log_path
        code = "import sys; from usar_arm.cli.main import main; sys.exit(main(sys.argv[1:]))"
        cmd = [sys.executable, "-c", code, "sim", "--port", "0", "--speed", str(speed),
               *extra_args]
        self._log = open(log_path, "w")  # closed in stop()
        self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=self._log,
                                     stderr=subprocess.STDOUT)
        self.pid = self.proc.pid
        deadline = time.monotonic() + start_timeout
        self.port = 0
        while not self.port:
            match = _LISTENING.search(log_path.read_text(errors="replace"))
            if match:
                self.port = int(match.group(1))
            elif self.proc.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise RuntimeError(f"the simulator did not start; its log:\n"
                                   f"{log_path.read_text(errors='replace')[-2000:]}")
            else:
                time.sleep(0.05)

    def sample(self) -> ProcSample:
        """RSS, thread count and CPU time of the server now."""
        status = Path(f"/proc/{self.pid}/status").read_text()
        rss = int(re.search(r"VmRSS:\s+(\d+)", status).group(1))  # type: ignore[union-attr]
        threads = int(re.search(r"Threads:\s+(\d+)", status).group(1))  # type: ignore[union-attr]
        stat = Path(f"/proc/{self.pid}/stat").read_text()
        fields = stat[stat.rindex(")") + 2:].split()
        cpu = (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime + stime
        wait = int(Path(f"/proc/{self.pid}/schedstat").read_text().split()[1]) / 1e9
        return ProcSample(time.monotonic(), rss, threads, cpu, wait)

    def alive(self) -> bool:
        return self.proc.poll() is None

    def stop(self, timeout: float = 20.0) -> int:
        """SIGTERM (a clean shutdown), SIGKILL after ``timeout``; returns the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)
        self._log.close()
        return int(self.proc.returncode)

    def log_text(self) -> str:
        return self.log_path.read_text(errors="replace")


def slope_per_min(samples: list[ProcSample], attr: str, after: float) -> float:
    """Least-squares slope of ``attr`` over the samples taken at or after wall time ``after``,
    in units per minute (0 with fewer than 3 samples)."""
    pts = [(s.t, float(getattr(s, attr))) for s in samples if s.t >= after]
    if len(pts) < 3:
        return 0.0
    mt = statistics.fmean(p[0] for p in pts)
    mv = statistics.fmean(p[1] for p in pts)
    den = sum((p[0] - mt) ** 2 for p in pts)
    return 60.0 * sum((p[0] - mt) * (p[1] - mv) for p in pts) / den if den else 0.0


def process_summary(samples: list[ProcSample], after: float) -> dict[str, Any]:
    """RSS/thread levels and slopes, and CPU use, of the samples after wall time ``after``."""
    window = [s for s in samples if s.t >= after]
    if len(window) < 2:
        return {}
    first, last = window[0], window[-1]
    return {
        "samples": len(window),
        "rss_kib_first": first.rss_kib, "rss_kib_last": last.rss_kib,
        "rss_kib_max": max(s.rss_kib for s in window),
        "rss_slope_kib_per_min": round(slope_per_min(samples, "rss_kib", after), 1),
        "threads_first": first.threads, "threads_last": last.threads,
        "threads_max": max(s.threads for s in window),
        "threads_slope_per_min": round(slope_per_min(samples, "threads", after), 3),
        "cpu_percent": round(100.0 * (last.cpu_s - first.cpu_s) / (last.t - first.t), 1),
        "runqueue_wait_percent": round(100.0 * (last.wait_s - first.wait_s) / (last.t - first.t),
                                       1),
    }


def log_counts(text: str) -> dict[str, int]:
    """How often the server logged the things the tools look for."""
    return {
        "warnings": text.count(" WARNING "),
        "errors": text.count(" ERROR "),
        "cannot_keep_up": text.count("cannot keep up"),
        "tracebacks": text.count("Traceback"),
        "connected": text.count(": connected"),
        "disconnected": text.count(": disconnected"),
    }


# ---------------------------------------------------------------------------------- clients


def quantiles(values: list[float]) -> dict[str, float]:
    """min / median / max (and count) of a list of numbers, rounded for reports."""
    if not values:
        return {"n": 0}
    return {"n": len(values), "min": round(min(values), 4),
            "median": round(statistics.median(values), 4), "max": round(max(values), 4)}


def stream_rates(walls: list[float], sims: list[float], name: str) -> dict[str, float]:
    """Rate and gaps of a stream of lines received at wall times ``walls`` (s) carrying the
    simulated times ``sims`` (s): ``<name>_per_wall_s`` and ``<name>_per_sim_s`` (lines per
    second), ``sim_speed`` (simulated s per wall s), ``max_gap_wall_s`` and ``max_gap_sim_s``
    (s); nothing with fewer than two lines."""
    n = len(walls)
    if n < 2:
        return {}
    span_sim, span_wall = sims[-1] - sims[0], walls[-1] - walls[0]
    return {f"{name}_per_wall_s": (n - 1) / span_wall if span_wall > 0 else 0.0,
            f"{name}_per_sim_s": (n - 1) / span_sim if span_sim > 0 else 0.0,
            "sim_speed": span_sim / span_wall if span_wall > 0 else 0.0,
            "max_gap_wall_s": max(b - a for a, b in itertools.pairwise(walls)),
            "max_gap_sim_s": max(b - a for a, b in itertools.pairwise(sims))}


def in_window(walls: array, t0: float, t1: float) -> list[int]:
    """Indices of the wall times (s) within [t0, t1]."""
    return [i for i, w in enumerate(walls) if t0 <= w <= t1]


@dataclass
class StreamClient:
    """What every well-behaved client does: connect, spawn a robot, send one command line at
    ``rate`` Hz on drift-free deadlines, probe ``GETCONF {Type Robot}`` every ``probe_every`` s
    and record its robot's status lines (wall and simulated time). Subclasses say which robot
    (:meth:`init_line`), which command (:meth:`command_line`) and what a received line means
    (:meth:`take`).

    Attributes:
        index: number of the client (phase of its commands, robot name).
        rate: command lines per second (0: none).
        probe_every: seconds between GETCONF probes (0: none).
    """

    index: int
    rate: float = 100.0
    probe_every: float = 1.0
    status_wall: array = field(default_factory=lambda: array("d"))
    status_sim: array = field(default_factory=lambda: array("d"))
    rtt_wall: array = field(default_factory=lambda: array("d"))
    rtt: array = field(default_factory=lambda: array("d"))
    sent_wall: array = field(default_factory=lambda: array("d"))
    spawned_at: float | None = None
    lost: str | None = None
    _writer: asyncio.StreamWriter | None = None
    _probe: asyncio.Future | None = None
    _t0: float = 0.0

    STATUS = "status"
    """Name of the status line in the summary's keys (``asta``, ``sta``)."""

    def init_line(self) -> str:
        """The INIT line that spawns this client's robot."""
        raise NotImplementedError

    def command_line(self, t: float) -> bytes:
        """The command line to send at wall time ``t`` (s)."""
        raise NotImplementedError

    def take(self, line: bytes, now: float) -> str | None:
        """Record a status or sensor line received at wall time ``now`` (s); a problem that
        ends the connection, or None."""
        raise NotImplementedError

    async def prepare(self) -> None:
        """Requests sent once the robot exists, before streaming starts (none here)."""

    def _spawned(self, now: float, sim: float) -> None:
        """Record a status line (wall ``now``, simulated ``sim``; s); the first one means the
        robot exists."""
        self.status_wall.append(now)
        self.status_sim.append(sim)

    async def run(self, port: int, stop: asyncio.Event, spawn_timeout: float = 60.0) -> None:
        """Connect, spawn and stream until ``stop`` is set; records a lost connection."""
        try:
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
        except OSError as exc:
            self.lost = f"connect failed: {exc}"
            return
        writer.transport.get_extra_info("socket").setsockopt(
            socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._writer = writer
        self._t0 = time.monotonic()
        read = asyncio.create_task(self._read(reader, stop))
        writer.write(f"{self.init_line()}\r\n".encode())
        try:
            await asyncio.wait_for(self._first_status(read), spawn_timeout)
            await asyncio.wait_for(self.prepare(), spawn_timeout)
            self.spawned_at = time.monotonic()
            tasks = [asyncio.create_task(self._stream(stop))]
            if self.probe_every > 0:
                tasks.append(asyncio.create_task(self._probes(stop)))
            await asyncio.wait([read, *tasks], return_when=asyncio.FIRST_COMPLETED)
            for t in tasks:
                t.cancel()
        except (TimeoutError, asyncio.TimeoutError):
            self.lost = self.lost or f"not ready within {spawn_timeout} s of INIT"
        finally:
            if not stop.is_set() and self.lost is None:
                self.lost = "the connection ended early"
            read.cancel()
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    async def _first_status(self, read: asyncio.Task) -> None:
        """Return once the first status line came (or the reader ended)."""
        while not self.status_wall and not read.done():
            await asyncio.sleep(0.02)

    async def _read(self, reader: asyncio.StreamReader, stop: asyncio.Event) -> None:
        try:
            while True:
                line = await reader.readline()
                if not line:
                    if not stop.is_set():
                        self.lost = "the server closed the connection"
                    return
                now = time.monotonic()
                if line.startswith(b"CONF") and self._probe is not None \
                        and not self._probe.done():
                    self._probe.set_result((now, line))
                    continue
                problem = self.take(line, now)
                if problem is not None:
                    self.lost = problem
                    return
        except (ConnectionError, OSError) as exc:
            if not stop.is_set():
                self.lost = f"connection error: {exc}"

    async def _stream(self, stop: asyncio.Event) -> None:
        if self.rate <= 0:
            await stop.wait()
            return
        assert self._writer is not None
        period = 1.0 / self.rate
        due = time.monotonic()
        while not stop.is_set():
            now = time.monotonic()
            self._writer.write(self.command_line(now))
            self.sent_wall.append(now)
            due += period
            if due < now - period:  # far behind (a stalled client): skip, do not burst
                due = now
            await asyncio.sleep(max(0.0, due - time.monotonic()))

    async def ask(self, request: bytes, timeout: float = 10.0) -> tuple[float, bytes] | None:
        """Send a GETCONF and wait for the next CONF line: (wall time it came, s; the line), or
        None after ``timeout`` s."""
        assert self._writer is not None
        self._probe = asyncio.get_running_loop().create_future()
        self._writer.write(request)
        try:
            return await asyncio.wait_for(self._probe, timeout)  # type: ignore[no-any-return]
        except (TimeoutError, asyncio.TimeoutError):
            return None

    async def _probes(self, stop: asyncio.Event) -> None:
        await asyncio.sleep(self.probe_every * ((self.index * 0.37) % 1.0))
        while not stop.is_set():
            sent = time.monotonic()
            got = await self.ask(b"GETCONF {Type Robot}\r\n")
            self.rtt_wall.append(sent)
            self.rtt.append(math.inf if got is None else got[0] - sent)
            await asyncio.sleep(self.probe_every)

    def summary(self, t0: float, t1: float) -> dict[str, Any]:
        """What this client saw in the wall-time window [t0, t1]: its status rates and gaps,
        command lines sent per second (``cmd_per_s``) and the GETCONF round trips (ms)."""
        idx = in_window(self.status_wall, t0, t1)
        out: dict[str, Any] = {"bot": self.index, "lost": self.lost,
                               self.STATUS: len(idx)}
        out.update(stream_rates([self.status_wall[i] for i in idx],
                                [self.status_sim[i] for i in idx], self.STATUS))
        out["cmd_per_s"] = len(in_window(self.sent_wall, t0, t1)) / (t1 - t0)
        rtts = [r for w, r in zip(self.rtt_wall, self.rtt, strict=True) if t0 <= w <= t1]
        out["probes"] = len(rtts)
        out["probe_timeouts"] = sum(1 for r in rtts if math.isinf(r))
        finite = sorted(r for r in rtts if math.isfinite(r))
        if finite:
            out["rtt_ms_median"] = 1e3 * statistics.median(finite)
            out["rtt_ms_max"] = 1e3 * finite[-1]
        return out


@dataclass
class Bot(StreamClient):
    """An arm client: spawns a KR60, streams full ``ACT`` lines (joint 1 follows a slow sine,
    ``amplitude`` rad at ``frequency`` Hz) and records every ``ASTA`` and joint 1's tracking
    error."""

    amplitude: float = 0.3
    frequency: float = 0.2
    track_err: array = field(default_factory=lambda: array("d"))

    STATUS = "asta"

    def command(self, t: float) -> float:
        """Joint-1 target (rad) at wall time ``t``."""
        return self.amplitude * math.sin(2 * math.pi * self.frequency * (t - self._t0)
                                         + self.index)

    def init_line(self) -> str:
        return (f"INIT {{ClassName {ROBOT_CLASS}}} {{Name R{self.index}}} "
                f"{{Location {3.0 * (self.index % 8)},{3.0 * (self.index // 8)},0}}")

    def command_line(self, t: float) -> bytes:
        return (f"ACT {{Name {ACTUATOR}}} {{Link 0}} {{Value {self.command(t):.4f}}} "
                "{Link 1} {Value -0.5000} {Link 2} {Value 0.3000} "
                "{Link 3} {Value 0.0000} {Link 4} {Value 0.2000} "
                "{Link 5} {Value 0.0000}\r\n").encode()

    def take(self, line: bytes, now: float) -> str | None:
        if not line.startswith(b"ASTA"):
            return None
        tm = _TIME.search(line)
        vals = _VALUE.findall(line)
        if tm is None or len(vals) != 6:
            return f"malformed ASTA: {line[:80]!r}"
        self._spawned(now, float(tm.group(1)))
        self.track_err.append(abs(float(vals[0]) - self.command(now)))
        return None

    def summary(self, t0: float, t1: float) -> dict[str, Any]:
        """As :meth:`StreamClient.summary`, ACT lines sent per second as ``act_per_s`` and the
        RMS tracking error of joint 1 (mrad)."""
        out = super().summary(t0, t1)
        out["act_per_s"] = out.pop("cmd_per_s")
        errs = [self.track_err[i] for i in in_window(self.status_wall, t0, t1)]
        if len(errs) >= 2:
            out["track_rms_mrad"] = 1e3 * math.sqrt(statistics.fmean(e * e for e in errs))
        return out


@dataclass
class Driver(StreamClient):
    """A ground-vehicle client: spawns a P3AT at one of the world's start poses, drives it with
    ``DRIVE`` at ``rate`` Hz (at most :data:`DRIVE_MAX_HZ`) and records every ``STA`` and every
    ``SEN`` by sensor type. The wheel speeds vary slowly within :data:`VEHICLE_MAX_SPEED`
    (forward and back, turning both ways), so the vehicles roam, turn and run into walls.

    Before streaming it asks each sensor type's ``ScanInterval`` (``GETCONF {Type T}``); a
    sensor whose CONF carries none (UDK's RangeScanner) is expected at :data:`SEN_INTERVAL_S`.
    A SEN line's simulated time is that of the STA of its status tick (UDK's INS carries none).
    """

    starts: tuple[str, ...] = ("RobotStart1", "RobotStart2", "RobotStart3")
    sen_wall: dict[str, array] = field(default_factory=dict)
    sen_sim: dict[str, array] = field(default_factory=dict)
    scan_interval: dict[str, float] = field(default_factory=dict)
    truth_xy: list[tuple[float, float, float]] = field(default_factory=list)
    closest: list[tuple[float, float]] = field(default_factory=list)

    STATUS = "sta"

    def __post_init__(self) -> None:
        self.rate = min(self.rate, DRIVE_MAX_HZ)

    def init_line(self) -> str:
        start = self.starts[self.index % len(self.starts)]
        return f"INIT {{ClassName {VEHICLE_CLASS}}} {{Name R{self.index}}} {{Start {start}}}"

    def wheels(self, t: float) -> tuple[float, float]:
        """(left, right) wheel speeds (rad/s) at wall time ``t`` (s): a forward part that
        reverses every 60 s and a turning part that swings every 15 s, at most 0.95 MaxSpeed
        (about 0.1 m/s on average: a minute takes a vehicle from its start to a wall)."""
        s = t - self._t0
        ahead = 0.75 * math.cos(2 * math.pi * s / 120.0 + self.index)
        turn = 0.2 * math.sin(2 * math.pi * s / 15.0 + 0.7 * self.index)
        return VEHICLE_MAX_SPEED * (ahead + turn), VEHICLE_MAX_SPEED * (ahead - turn)

    def command_line(self, t: float) -> bytes:
        left, right = self.wheels(t)
        return f"DRIVE {{Left {left:.4f}}} {{Right {right:.4f}}}\r\n".encode()

    async def prepare(self) -> None:
        """Ask each sensor type's ScanInterval (s)."""
        for kind in SEN_INTERVAL_S:
            got = await self.ask(f"GETCONF {{Type {kind}}}\r\n".encode())
            match = _SCAN_INTERVAL.search(got[1]) if got is not None else None
            self.scan_interval[kind] = (float(match.group(1)) if match
                                        else SEN_INTERVAL_S[kind])

    def take(self, line: bytes, now: float) -> str | None:
        if line.startswith(b"STA"):
            tm = _TIME.search(line)
            if tm is None:
                return f"malformed STA: {line[:80]!r}"
            self._spawned(now, float(tm.group(1)))
        elif line.startswith(b"SEN") and self.status_sim:
            kind = _TYPE.search(line)
            if kind is None:
                return f"malformed SEN: {line[:80]!r}"
            name = kind.group(1).decode()
            self.sen_wall.setdefault(name, array("d")).append(now)
            self.sen_sim.setdefault(name, array("d")).append(self.status_sim[-1])
            if name == "GroundTruth":
                self._truth(line, now)
            elif name == "RangeScanner":
                self._scan(line, now)
        return None

    def _truth(self, line: bytes, now: float) -> None:
        """Keep the chassis' x, y (m) of a GroundTruth line received at wall time ``now``."""
        loc = _LOCATION.search(line)
        if loc is not None:
            x, y, *_ = (float(v) for v in loc.group(1).split(b","))
            self.truth_xy.append((now, x, y))

    def _scan(self, line: bytes, now: float) -> None:
        """Keep the nearest range (m) of a RangeScanner line received at wall time ``now``."""
        ranges = _RANGE.search(line)
        if ranges is not None:
            self.closest.append((now, min(float(v) for v in ranges.group(1).split(b","))))

    def travel(self, t0: float, t1: float) -> float:
        """Path length (m) of the chassis in the wall-time window [t0, t1], from GroundTruth."""
        pts = [(x, y) for w, x, y in self.truth_xy if t0 <= w <= t1]
        return sum(math.dist(a, b) for a, b in itertools.pairwise(pts))

    def summary(self, t0: float, t1: float) -> dict[str, Any]:
        """As :meth:`StreamClient.summary`, DRIVE lines sent per second as ``drive_per_s``, and
        per sensor type T ``sen_T_per_sim_s`` (lines per simulated s) beside ``sen_T_expected``
        (1 / its ScanInterval), the path driven (``travel_m``, m) and the
        nearest thing the scanner saw (``closest_m``, m: about 0.1-0.2 m against a wall)."""
        out = super().summary(t0, t1)
        out["drive_per_s"] = out.pop("cmd_per_s")
        out["travel_m"] = self.travel(t0, t1)
        near = [r for w, r in self.closest if t0 <= w <= t1]
        if near:
            out["closest_m"] = min(near)
        for kind in sorted(set(SEN_INTERVAL_S) | set(self.sen_wall)):
            walls = self.sen_wall.get(kind, array("d"))
            idx = in_window(walls, t0, t1)
            sims = [self.sen_sim[kind][i] for i in idx]
            span = sims[-1] - sims[0] if len(sims) >= 2 else 0.0
            out[f"sen_{kind}_per_sim_s"] = (len(sims) - 1) / span if span > 0 else 0.0
            interval = self.scan_interval.get(kind, SEN_INTERVAL_S.get(kind, 0.0))
            out[f"sen_{kind}_expected"] = 1.0 / interval if interval > 0 else 0.0
        return out


ARM_FIGURES = ("asta_per_wall_s", "asta_per_sim_s", "sim_speed", "max_gap_wall_s",
               "max_gap_sim_s", "track_rms_mrad", "act_per_s", "rtt_ms_median", "rtt_ms_max")
"""The figures every summary of arm clients carries (the tools read them without checking)."""
VEHICLE_FIGURES = ("sta_per_wall_s", "sta_per_sim_s", "sim_speed", "max_gap_wall_s",
                   "max_gap_sim_s", "drive_per_s", "rtt_ms_median", "rtt_ms_max", "travel_m")
"""The figures every summary of vehicle clients carries."""


def summarise_bots(rows: list[dict[str, Any]], figures: tuple[str, ...] = ARM_FIGURES
                   ) -> dict[str, Any]:
    """min/median/max over bots of each per-bot figure: every float the rows carry, and
    ``figures`` always (``{"n": 0}`` when no bot has one)."""
    keys = sorted({*figures, *(k for r in rows for k, v in r.items()
                                   if isinstance(v, float))})
    out: dict[str, Any] = {k: quantiles([r[k] for r in rows if k in r]) for k in keys}
    out["bots"] = len(rows)
    out["lost"] = [f"bot {r['bot']}: {r['lost']}" for r in rows if r["lost"]]
    out["probe_timeouts"] = sum(r.get("probe_timeouts", 0) for r in rows)
    return out


# ---------------------------------------------------------------------------------- abuse

FLOOD_KINDS = ("act", "malformed", "unknown", "binary", "oversized")


@dataclass
class Flooder:
    """One client sending ``rate`` lines per second of one ``kind`` (see FLOOD_KINDS).

    ``act`` spawns a robot first and floods valid ACT lines for it; the other kinds flood junk.
    """

    kind: str
    rate: float = 10_000.0
    sent_lines: int = 0
    sent_bytes: int = 0
    lost: str | None = None
    local_port: int = 0
    started: float = 0.0
    stopped: float = 0.0

    @property
    def achieved_rate(self) -> float:
        """Lines per second actually sent (TCP back-pressure may hold the flooder back)."""
        span = (self.stopped or time.monotonic()) - self.started
        return self.sent_lines / span if self.started and span > 0 else 0.0

    def _line(self, i: int) -> bytes:
        if self.kind == "act":
            return (f"ACT {{Name {ACTUATOR}}} {{Link 0}} {{Value {0.1 * math.sin(i / 500):.4f}}}"
                    " {Link 1} {Value -0.5}\r\n").encode()
        if self.kind == "malformed":
            return [b"ASTA {Time {broken}}\r\n", b"ACT {Name KR60Arm} {Link x} {Value 1}\r\n",
                    b"GETCONF {Type Actuator\r\n", b"}}}{{{\r\n"][i % 4]
        if self.kind == "unknown":
            return f"FROB{i % 7} {{Key {i}}}\r\n".encode()
        if self.kind == "binary":
            return os.urandom(60).replace(b"\n", b"x").replace(b"\r", b"y") + b"\n"
        if self.kind == "oversized":
            return b"ACT {Name KR60Arm} " + b"{Link 0} {Value 0.1} " * 4000 + b"\r\n"
        raise ValueError(f"unknown flood kind {self.kind!r}; known: {', '.join(FLOOD_KINDS)}")

    async def run(self, port: int, stop: asyncio.Event) -> None:
        try:
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
        except OSError as exc:
            self.lost = f"connect failed: {exc}"
            return
        self.local_port = int(writer.get_extra_info("sockname")[1])
        drain_reads = asyncio.create_task(self._discard(reader))
        if self.kind == "act":
            writer.write(f"INIT {{ClassName {ROBOT_CLASS}}} {{Name Flood}} "
                         "{Start RobotStart1}\r\n".encode())
            await asyncio.sleep(0.5)
        self.started = time.monotonic()
        owed, last = 0.0, self.started
        try:
            while not stop.is_set():
                now = time.monotonic()
                owed = min(owed + self.rate * (now - last), max(1.0, self.rate * 0.05))
                last = now
                n = int(owed)
                if n:
                    owed -= n
                    lines = b"".join(self._line(self.sent_lines + k) for k in range(n))
                    writer.write(lines)
                    self.sent_lines += n
                    self.sent_bytes += len(lines)
                    await writer.drain()  # TCP back-pressure limits what we can push
                await asyncio.sleep(0.01)
            self.stopped = time.monotonic()
        except (ConnectionError, OSError) as exc:
            self.lost = f"connection error: {exc}"
        finally:
            drain_reads.cancel()
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    @staticmethod
    async def _discard(reader: asyncio.StreamReader) -> None:
        with contextlib.suppress(Exception):
            while await reader.read(65536):
                pass


async def midline_disconnects(port: int, count: int) -> list[int]:
    """``count`` clients that connect, send part of a line (some after a full INIT) and vanish;
    returns their local ports."""
    ports = []
    for i in range(count):
        with contextlib.suppress(OSError):
            _, writer = await asyncio.open_connection("127.0.0.1", port)
            ports.append(int(writer.get_extra_info("sockname")[1]))
            if i % 2:
                writer.write(b"INIT {ClassName USARBot.KR60} {Start RobotStart1}\r\n")
                await asyncio.sleep(0.05)
            writer.write(b"GETCONF {Type Actua")
            await writer.drain()
            if i % 3 == 0:
                writer.transport.abort()  # RST instead of FIN
            else:
                writer.close()
            await asyncio.sleep(0.02)
    return ports


_SUMMARY = re.compile(r"127\.0\.0\.1:(\d+): disconnected after [0-9.]+ s(?:; robot destroyed)?; "
                      r"(\d+) lines, served (\d+)(?:, refused (\d+) \(([^)]*)\))?; "
                      r"(\d+) bytes in")


def disconnect_summaries(log: str) -> dict[int, dict[str, Any]]:
    """The server's per-connection summaries, by client port: lines, served, refused by kind."""
    out: dict[int, dict[str, Any]] = {}
    for match in _SUMMARY.finditer(log):
        kinds = {}
        for part in (match.group(5) or "").split(", "):
            if part:
                kind, _, n = part.rpartition(" ")
                kinds[kind] = int(n)
        out[int(match.group(1))] = {"lines": int(match.group(2)), "served": int(match.group(3)),
                                    "refused": int(match.group(4) or 0), "refused_by_kind": kinds,
                                    "bytes_in": int(match.group(6))}
    return out


def machine_load() -> str:
    """The load averages (1, 5, 15 min) and CPU count, for reports."""
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f} {five:.2f} {fifteen:.2f} on {os.cpu_count()} CPUs"


def tool_parser(doc: str | None, clients: int, rate: float,
                epilog: str | None = None) -> argparse.ArgumentParser:
    """The parser every simulator campaign starts from: its description (the docstring's first
    paragraph) and epilog (the next two, unless given), ``--clients`` and ``--rate`` with this
    tool's defaults, and the ``--server-log`` / ``--json`` outputs."""
    paragraphs = (doc or "").split("\n\n")
    p = argparse.ArgumentParser(
        description=paragraphs[0] or None, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=epilog if epilog is not None else "\n\n".join(paragraphs[1:3]))
    p.add_argument("--clients", type=int, default=clients,
                   help=f"well-behaved clients (default {clients})")
    p.add_argument("--rate", type=float, default=rate,
                   help=f"ACT lines/s per client (default {rate:g})")
    p.add_argument("--server-log", type=Path, help="keep the simulator's log here")
    p.add_argument("--json", type=Path, help="write the results to this file")
    return p


async def sample_server(server: ServerProcess | None, samples: list[ProcSample],
                        stop: asyncio.Event, every: float) -> None:
    """Append a sample of the server's process to ``samples`` every ``every`` s until ``stop``
    is set or the process ends (nothing without a process of ours)."""
    while not stop.is_set() and server is not None and server.alive():
        samples.append(server.sample())
        await asyncio.sleep(every)


def sample_rows(samples: list[ProcSample], started: float, digits: int = 2) -> list[list]:
    """[t since ``started`` (s), RSS (KiB), threads, CPU (s)] of each sample, for the JSON."""
    return [[round(s.t - started, digits), s.rss_kib, s.threads, round(s.cpu_s, 2)]
            for s in samples]


def campaign(name: str, server_log: Path | None,
             run: Callable[[ServerProcess], Awaitable[dict[str, Any]]]
             ) -> tuple[dict[str, Any], ServerProcess, int, Path]:
    """Start a simulator process (logging to ``server_log``, else a fresh temporary folder
    named after the tool), run the campaign against it and stop it: (the campaign's result
    with ``server_alive``, the process, its exit code, its log's path)."""
    log_path = server_log or Path(tempfile.mkdtemp(prefix=f"{name}_")) / "sim.log"
    server = ServerProcess(log_path)
    try:
        result = asyncio.run(run(server))
        result["server_alive"] = server.alive()
    finally:
        code = server.stop()
    return result, server, code, log_path


def write_result(result: dict[str, Any], path: Path | None) -> None:
    """The result as JSON into ``path`` (--json), else on stdout."""
    text = json.dumps(result, indent=1) + "\n"
    if path:
        path.write_text(text)
    else:
        sys.stdout.write(text)
