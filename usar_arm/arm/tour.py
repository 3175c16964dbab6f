"""The calibration tour on a live arm: configurations chosen for observability, one motion
through them within what each joint's drive can follow, and every tip-sensor reading taken on
the way with the joint values of the same instant.

Readings: the server prints the sensor's pose (SEN, 3 decimals truncated) and the joint values
(ASTA, 4 decimals rounded) ten times a second from one state with the same ``Time``; each SEN is
paired with the ASTA of that time, in motion as at rest, and a reading repeated while the arm
rests is kept once. The motion moves every printed number through its step, so the truncation
dithers by itself.

Speed: the tour runs at the description's limits, except where the arm's identified drive
(:class:`~usar_arm.control.drive.DriveModel`) could not follow them: a position drive's
stiffness is its force limit (UDK's PhysX drives, the embedded simulator), so a joint whose
feedforward needs the target more than :data:`DRIVE_REACH` (rad or m) ahead of it runs into
that limit. The Fanuc's rail (lag 0.35 s, inertia 0.35 s^2 at 1 m/s and 2 m/s^2: under-damped,
:data:`RINGING_REACH`) and its last axis (lag 0.5 s at 9 rad/s) are capped hard; the KR60's
last axis (lag 0.2 s at 5.6 rad/s) by a tenth.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from usar_arm.arm.facade import Arm
from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.observability import select_poses
from usar_arm.control.drive import DriveModel
from usar_arm.control.timing import stop_at_waypoints
from usar_arm.control.trajectory import MotionLimits, Trajectory
from usar_arm.core.errors import (
    CalibrationError,
    ExecutionAbortedError,
    InvalidInputError,
    ResponseTimeoutError,
)
from usar_arm.core.spatial import Array
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.inbox import Received
from usar_arm.usarsim.numbers import ROUNDED_SCALARS

log = logging.getLogger("usar_arm.arm.tour")

SPEED_SCALES = (1.0, 0.5, 0.25)
"""Fractions of the (drive-capped) limits the tour tries, slower after an aborted attempt: how
closely the arm follows the plan matters only for safety (the executor's tracking bound), since
every reading pairs a sensor pose with the joint values of the same instant."""
DRIVE_REACH = 1.0
"""How far (rad or m) the tour's feedforward may put a joint's target ahead of it: the error at
which its drive's force saturates (stiffness = force limit: 1 rad or 1 m)."""
RINGING_REACH = 0.5
"""The same for an under-damped drive (lag^2 < 4 inertia), which overshoots and rings, and is
pushed about by what it carries (the Fanuc's carriage under the arm): measured, the rail
leaves the tracking bound on the tour at 0.75 and stays within it at 0.5."""
SETTLE_S = 0.3
"""The tour's end is not a goal: it settles this long (s) at most."""

Progress = Callable[[int, int], None]
"""Called with (poses reached, poses planned)."""


CLEARANCE = 0.05
"""How far (m) the tour's configurations stay from the scene and from the arm's own links: the
as-learnt description is a few millimetres off, and the tour runs fast."""


def clear_of(arm: Arm, scene: str | None, start: Array,
             clearance: float = CLEARANCE) -> Callable[[Array], bool]:
    """Whether a configuration is free in ``scene`` and ``clearance`` (m) clear of everything
    the arm is not already that close to at ``start`` (where it stands, untouched): a rail's
    carriage rides a few centimetres over the floor at every configuration, and a pair that
    close at the start may stay that close, though never touch."""
    scene_of = arm.world(scene).scene
    padded = arm.robot.collision_world(scene_of, padding=clearance)
    exact = arm.robot.collision_world(scene_of)
    near = set(padded.contacts(np.asarray(start, float)))

    def free(q: Array) -> bool:
        if not padded.in_collision(q):
            return True
        return not exact.in_collision(q) and set(padded.contacts(q)) <= near

    return free


def choose_configurations(arm: Arm, count: int, scene: str | None, seed: int) -> Array:
    """``count`` configurations :func:`clear_of` ``scene`` from where the arm stands now,
    maximising the identification Jacobian's smallest singular value."""
    free = clear_of(arm, scene, arm.joints())
    frame = str(arm.robot.tip_sensor)
    chosen = select_poses(arm.urdf, frame, count, free, seed)
    return np.asarray(chosen, float)


def at_rest(arm: Arm, tolerance: float = 1e-3, timeout: float = 10.0) -> Array:
    """The arm's joints once two ASTA readings 0.3 s of simulated time apart differ by less
    than ``tolerance`` (rad or m) in every joint (an aborted tour leaves it moving). Each
    wait for a reading is bounded by ``timeout`` / 2 s (a busy machine slows the simulator)."""
    deadline = time.monotonic() + timeout
    q, t = arm.joints(), arm.asta_time()
    while True:
        later = arm.joints(newer_than=t + 0.3, timeout=timeout / 2)
        if float(np.max(np.abs(later - q))) < tolerance:
            return later
        if time.monotonic() > deadline:
            raise CalibrationError(f"the arm did not come to rest within {timeout:.0f} s "
                                   f"(still moving by {np.max(np.abs(later - q)):.4f})")
        q, t = later, arm.asta_time()


def tour_order(start: Array, configurations: Array, velocity: Array) -> Array:
    """``configurations`` in nearest-neighbour order from ``start``, distance being the time
    the slowest joint needs at its velocity limit (s): a short tour gives the same readings'
    spread in less time."""
    left = list(range(len(configurations)))
    order: list[int] = []
    here = np.asarray(start, float)
    while left:
        times = [float(np.max(np.abs(configurations[k] - here) / velocity)) for k in left]
        k = left.pop(int(np.argmin(times)))
        order.append(k)
        here = configurations[k]
    return np.asarray(configurations, float)[order]


def drive_caps(drive: DriveModel, velocity: Array, acceleration: Array) -> Array:
    """Per joint, the fraction (<= 1) of its velocity and acceleration limits its drive can
    follow: the feedforward's lead lag v + inertia a kept within the drive's reach (see the
    module)."""
    inertia = drive.inertia if drive.inertia is not None else np.zeros_like(drive.lag)
    need = drive.lag * velocity + inertia * acceleration
    reach = np.where(drive.lag ** 2 < 4 * inertia, RINGING_REACH, DRIVE_REACH)
    out: Array = np.minimum(1.0, reach / np.maximum(need, 1e-9))
    return out


def tour_limits(arm: Arm, scale: float) -> MotionLimits:
    """The description's limits at ``scale``, each joint capped where its identified drive
    could not follow (see the module); the drive is identified first if it is not yet."""
    limits = MotionLimits.from_chain(arm.robot.chain)
    executor = arm.executor()
    drive = executor.drive or executor.identify()
    cap = drive_caps(drive, limits.velocity, limits.acceleration) * scale
    capped = np.flatnonzero(cap < scale)
    if len(capped):
        names = arm.robot.chain.joint_names
        log.info("the tour caps %s at %s of their limits (their drives could not follow)",
                 ", ".join(names[j] for j in capped), ", ".join(f"{cap[j]:.2f}" for j in capped))
    return MotionLimits(limits.lower, limits.upper, limits.velocity * cap,
                        limits.acceleration * cap, limits.jerk * cap)


def plan_tour(arm: Arm, configurations: Array, scene: str | None, limits: MotionLimits
              ) -> Trajectory:
    """One trajectory from the arm's joints through ``configurations`` (nearest first) along
    collision-free paths, at rest at every waypoint, timed at ``limits`` (passing through
    them instead was measured no faster: the legs turn too sharply)."""
    start = at_rest(arm)
    waypoints = [start[None, :]]
    for q in tour_order(start, configurations, limits.velocity):
        plan = arm.plan(joints=q, scene=scene, start=start, speed_scale=1.0)
        waypoints.append(plan.waypoints[1:])
        start = plan.waypoints[-1]
    names = arm.robot.chain.joint_names
    return stop_at_waypoints(names, np.vstack(waypoints), limits).sample(motion="ptp")


class Recorder:
    """Every tip-sensor reading the server streams, paired with the ASTA line of the same
    simulated time (the server prints both from one state, ten times a second)."""

    def __init__(self, actuator: str, tip_sensor: str, wire_links: tuple[int, ...]):
        self.actuator, self.tip_sensor, self.links = actuator, tip_sensor.lower(), wire_links
        self.joints: dict[float, tuple[Array, float]] = {}
        self.poses: dict[float, tuple[Array, Array, float, float]] = {}

    def __call__(self, rec: Received) -> None:
        msg = rec.message
        if isinstance(msg, m.Asta) and msg.name == self.actuator and msg.time is not None:
            q = msg.joints(self.links)
            if q is not None:
                self.joints[msg.time] = (np.array(q, float), rec.step("Value"))
        elif (isinstance(msg, m.Sen) and (msg.name or "").lower() == self.tip_sensor
              and msg.time is not None and msg.location is not None
              and msg.orientation is not None):
            self.poses[msg.time] = (np.array(msg.location, float),
                                    np.array(msg.orientation, float), rec.step("Location"),
                                    rec.step("Orientation"))

    def measurements(self) -> list[Measurement]:
        """One measurement per distinct printed reading, in time order (a reading repeated
        while the arm rests carries no new information and would weigh that pose more)."""
        out: list[Measurement] = []
        seen: set[tuple[float, ...]] = set()
        for t in sorted(set(self.joints) & set(self.poses)):
            q, step_q = self.joints[t]
            loc, rpy, step_m, step_rad = self.poses[t]
            key = tuple(np.concatenate([q, loc, rpy]).tolist())
            if key in seen:
                continue
            seen.add(key)
            out.append(Measurement(q=q, position=loc, rpy=rpy, step_m=step_m,
                                   step_rad=step_rad, step_q=step_q, q_rounded=ROUNDED_SCALARS,
                                   label=f"t={t:.4f} s"))
        return out


def collect(arm: Arm, configurations: Array, scene: str | None,
            progress: Progress | None = None) -> list[Measurement]:
    """Move through ``configurations`` in one motion (see the module; slower after an aborted
    attempt) and keep every tip-sensor reading taken on the way, with the joint values the
    server reported at the same simulated time."""
    client = arm.client
    if client is None:
        raise InvalidInputError("calibration needs an arm connected to a server")
    recorder = Recorder(str(arm.robot.actuator), str(arm.robot.tip_sensor),
                        arm.robot.wire_links)
    previous = arm.executor().options  # the tour's short settle is for the tour only
    options = replace(previous, settle_timeout=SETTLE_S)
    unsubscribe = client.subscribe(recorder)
    try:
        for scale in SPEED_SCALES:
            try:
                tour = plan_tour(arm, configurations, scene, tour_limits(arm, scale))
                arm.execute(tour, options=options)
                break
            except (ExecutionAbortedError, ResponseTimeoutError) as exc:
                if scale == SPEED_SCALES[-1]:
                    raise
                log.warning("the calibration tour at %.0f %% of the limits was aborted (%s); "
                            "touring again slower", 100 * scale, exc)
    finally:
        unsubscribe()
        arm.executor(previous)
    if progress is not None:
        progress(len(configurations), len(configurations))
    return recorder.measurements()
