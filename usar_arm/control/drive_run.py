"""Driving a ground vehicle over the wire: a velocity script or pure pursuit, recorded.

The loop is paced by the vehicle's GroundTruth stream (10 Hz on a P3AT): at each new reading it
takes the pose from the chosen localisation (``truth``, ``odometry`` or ``ins``), asks the
controller for (v, w), maps it to wheel spins (:func:`~usar_arm.control.skid.wheel_speeds`,
within the vehicle's reported maximum) or, on an Ackermann vehicle, to a spin and a front steer
(:func:`~usar_arm.control.ackermann.ackermann_command`) and sends ``DRIVE``. Every SEN line
is recorded as it arrives (on the client's reader thread). Every wait is bounded by the
client's timeout; a drive that overruns its time budget (simulated seconds) ends with
``reached`` False. Ctrl-C stops the vehicle (``DRIVE {Left 0} {Right 0}``, or ``{Speed 0}``)
and keeps the record, marked ``interrupted``.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from usar_arm.control.ackermann import ackermann_command, drive_message
from usar_arm.control.drive_record import (
    Command,
    DriveRecord,
    PoseTrack,
    Scan,
    compose,
    odom_origin,
)
from usar_arm.control.pursuit import PurePursuit, PursuitOptions, Segment, script_command
from usar_arm.control.skid import wheel_speeds
from usar_arm.control.vehicle_wire import (
    VehicleInfo,
    height_zup,
    odometry_planar,
    planar_wire,
)
from usar_arm.core.errors import InvalidInputError, ResponseTimeoutError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import Received, UsarClient

log = logging.getLogger("usar_arm.control")

Localisation = Literal["truth", "odometry", "ins"]
Progress = Callable[[int, int], None]
"""Called with (done, total): centimetres of path, or tenths of a second of a script."""


@dataclass(frozen=True)
class DriveOptions:
    """How to drive: the pose the controller steers on, the time budget (simulated s) beyond
    the nominal duration, and the seconds any single wait for a reading may take."""

    localisation: Localisation = "truth"
    budget_factor: float = 3.0
    budget_extra_s: float = 30.0
    timeout_s: float = 5.0


class _Recorder:
    """Collects the vehicle's SEN lines as they arrive (reader thread), under a lock."""

    def __init__(self, vehicle: VehicleInfo):
        self.vehicle = vehicle
        self.lock = threading.Lock()
        self.truth: list[tuple[float, float, float, float]] = []
        self.odometry: list[tuple[float, float, float, float]] = []
        self.ins: list[tuple[float, float, float, float]] = []
        self.scans: list[Scan] = []
        self.height: float | None = None
        self.last_time = 0.0

    def __call__(self, rec: Received) -> None:
        msg, v = rec.message, self.vehicle
        with self.lock:
            t = getattr(msg, "time", None)
            if t is not None:
                self.last_time = float(t)
            if isinstance(msg, m.Sen) and msg.name == v.truth and msg.location and \
                    msg.orientation is not None:
                self.truth.append((self.last_time, *planar_wire(msg.location, msg.orientation)))
                if self.height is None:
                    self.height = height_zup(msg.location)
            elif isinstance(msg, m.Odometry) and msg.name == v.odometry:
                self.odometry.append((self.last_time, *odometry_planar(msg.pose)))
            elif isinstance(msg, m.Ins) and msg.name == v.ins:  # (no Time in UDK: the last one)
                self.ins.append((self.last_time, *planar_wire(msg.location, msg.orientation)))
            elif isinstance(msg, m.RangeScan) and v.scanner and msg.name == v.scanner.name:
                self.scans.append(Scan(self.last_time, msg.ranges, msg.fov))

    def pose(self, source: Localisation) -> tuple[float, float, float] | None:
        """The latest pose from ``source`` (odometry: anchored at the first ground truth)."""
        with self.lock:
            if source == "truth":
                return self.truth[-1][1:] if self.truth else None
            if source == "ins":
                return self.ins[-1][1:] if self.ins else None
            if not self.odometry or not self.truth:
                return None
            origin = odom_origin(self.truth[0][1:], self.odometry[0][1:])
            last = self.odometry[-1][1:]
        x, y, yaw = compose(origin, np.asarray([last], dtype=float))[0]
        return float(x), float(y), float(yaw)

    def record(self, commands: list[Command], reached: bool, interrupted: bool,
               goals: Sequence[tuple[float, float]]) -> DriveRecord:
        """What was recorded so far."""
        with self.lock:
            return DriveRecord(self.vehicle, PoseTrack.of(self.truth),
                               PoseTrack.of(self.odometry), PoseTrack.of(self.ins),
                               tuple(self.scans), tuple(commands), self.height or 0.0,
                               reached, interrupted, tuple(goals))


Controller = Callable[[float, tuple[float, float, float]], "tuple[float, float] | None"]
"""(seconds since the start, pose) -> (v, w), or None when the drive is over."""


class Driver:
    """Drives one spawned vehicle over ``client``; one drive per :meth:`follow` / :meth:`play`.
    """

    def __init__(self, client: UsarClient, vehicle: VehicleInfo, options: DriveOptions):
        if vehicle.truth is None:
            raise InvalidInputError(f"{vehicle.name} reports no GroundTruth sensor: the drive "
                                    "is paced and judged by it")
        wanted = {"odometry": vehicle.odometry, "ins": vehicle.ins, "truth": vehicle.truth}
        if wanted[options.localisation] is None:
            raise InvalidInputError(f"{vehicle.name} has no {options.localisation} sensor to "
                                    "steer on")
        self.client = client
        self.vehicle = vehicle
        self.options = options
        self.steer = 0.0
        """An Ackermann vehicle's front steer in force (rad, REP-103)."""

    def follow(self, waypoints: Sequence[tuple[float, float]], pursuit_options: PursuitOptions,
               progress: Progress | None = None) -> DriveRecord:
        """Pure pursuit from where the vehicle stands through ``waypoints`` (m, map frame); an
        Ackermann vehicle never turns on the spot (its pursuit follows arcs only)."""
        if self.vehicle.ackermann:  # (it cannot turn on the spot: arcs only)
            pursuit_options = dataclasses.replace(pursuit_options, turn_in_place_rad=math.pi)
        recorder = _Recorder(self.vehicle)
        unsubscribe = self.client.subscribe(recorder)
        try:
            start = self._first_pose(recorder)
            pursuit = PurePursuit(start[:2], waypoints, pursuit_options)
            speed = min(pursuit_options.max_speed_mps, self.vehicle.max_speed)
            budget = pursuit.length_m / speed * self.options.budget_factor + \
                self.options.budget_extra_s
            total = max(1, round(pursuit.length_m * 100))

            def step(elapsed: float, pose: tuple[float, float, float]
                     ) -> tuple[float, float] | None:
                if progress is not None:
                    progress(min(total, round(pursuit.progress_m(pose[0], pose[1]) * 100)),
                             total)
                command = pursuit.command(*pose)
                if pursuit.done and progress is not None:
                    progress(total, total)
                return None if pursuit.done else command

            return self._run(recorder, step, budget, waypoints)
        finally:
            unsubscribe()

    def play(self, segments: Sequence[Segment], progress: Progress | None = None
             ) -> DriveRecord:
        """Hold each segment's (v, w) for its duration (simulated s), open loop."""
        recorder = _Recorder(self.vehicle)
        unsubscribe = self.client.subscribe(recorder)
        duration = sum(s.duration_s for s in segments)
        total = max(1, round(duration * 10))

        def step(elapsed: float, pose: tuple[float, float, float]) -> tuple[float, float] | None:
            if progress is not None:
                progress(min(total, round(elapsed * 10)), total)
            return script_command(segments, elapsed)

        try:
            self._first_pose(recorder)
            return self._run(recorder, step, duration + self.options.budget_extra_s, ())
        finally:
            unsubscribe()

    def _first_pose(self, recorder: _Recorder) -> tuple[float, float, float]:
        """Wait (bounded) for a ground truth newer than the subscription; the true pose."""
        assert self.vehicle.truth is not None
        sen = self._next_truth(None)
        assert sen.location is not None and sen.orientation is not None
        return planar_wire(sen.location, sen.orientation)

    def _next_truth(self, after: float | None) -> m.Sen:
        """The next GroundTruth reading after ``after`` (s; None: after the latest one)."""
        truth = self.vehicle.truth
        assert truth is not None
        if after is None:
            latest = self.client.latest_sen(truth)
            after = latest.time if latest is not None else None
        sen = self.client.wait_sen(truth, after_time=after, timeout=self.options.timeout_s)
        if sen.location is None or sen.orientation is None:
            raise InvalidInputError(f"GroundTruth {truth} sent no Location/Orientation: {sen}")
        return sen

    def _run(self, recorder: _Recorder, step: Controller, budget_s: float,
             goals: Sequence[tuple[float, float]]) -> DriveRecord:
        commands: list[Command] = []
        reached, interrupted = False, False
        t0 = last = self._next_truth(None).time or 0.0
        try:
            while True:
                sen = self._next_truth(last)
                last = sen.time or last
                if last - t0 > budget_s:
                    break
                assert sen.location is not None and sen.orientation is not None
                pose = (planar_wire(sen.location, sen.orientation)
                        if self.options.localisation == "truth"
                        else recorder.pose(self.options.localisation))
                if pose is None:  # (odometry and INS lines are not cached: the recorder's)
                    if last - t0 > self.options.timeout_s:
                        raise ResponseTimeoutError(f"{self.options.localisation} readings",
                                                   self.options.timeout_s,
                                                   "the vehicle streams none to steer on")
                    continue
                asked = step(last - t0, pose)
                if asked is None:
                    reached = True
                    break
                line, command = self._command(last, asked[0], asked[1])
                self.client.send(line)
                commands.append(command)
        except KeyboardInterrupt:
            interrupted = True
        finally:
            self._stop(commands, last)
        return recorder.record(commands, reached, interrupted, goals)

    def _command(self, t: float, v: float, w: float) -> tuple[m.Drive, Command]:
        """The DRIVE line for (v m/s, w rad/s) at time ``t`` (s) and its record: the sides'
        wheel spins of a skid-steered vehicle, or an Ackermann vehicle's spin and steer."""
        veh = self.vehicle
        if not veh.ackermann:
            left, right, clamped = wheel_speeds(v, w, veh.wheel_radius, veh.wheel_separation,
                                                veh.max_wheel_speed)
            return m.Drive(left, right), Command(t, v, w, left, right, clamped)
        cmd = ackermann_command(v, w, veh.wheel_radius, veh.wheel_base, veh.max_wheel_speed,
                                veh.max_steer, self.steer)
        if cmd.turn_refused:
            log.info("a turn on the spot (w %.3f rad/s, v 0) cannot be driven by an Ackermann "
                     "vehicle: it stands still, steer kept", w)
        self.steer = cmd.steer
        return drive_message(cmd), Command(t, v, w, cmd.speed, cmd.speed,
                                           cmd.speed_clamped or cmd.steer_clamped, cmd.steer)

    def _stop(self, commands: list[Command], t: float) -> None:
        """DRIVE 0, 0 (or Speed 0, steer kept; also after Ctrl-C or a failed wait), recorded
        as a command."""
        line, command = self._command(t, 0.0, 0.0)
        try:
            self.client.send(line)
        except OSError:
            return
        commands.append(command)
