"""The live node of a ground vehicle (``usar-arm ros --robot P3AT``, docs/ros.md), written
once for both middlewares (a :class:`~usar_arm.ros.transport.Transport` each).

It spawns and learns the vehicle (:class:`~usar_arm.description.platform.LivePlatform`) and
serves:

* ``cmd_vel`` (geometry_msgs/Twist): linear.x, angular.z -> one DRIVE line per message
  (:func:`~usar_arm.ros.drive.velocity_command`: wheel speeds clamped keeping the ratio, or an
  Ackermann vehicle's spin and front steer); a NaN or infinite command stops the robot;
  without a command for ``cmd_timeout`` s the robot is stopped;
* ``odom`` (nav_msgs/Odometry, odom -> base_footprint) and the same transform on ``tf``, from
  the sensor ``odom_sensor`` names (default: the first INS);
* ``scan`` (sensor_msgs/LaserScan) per range scanner line, in the scanner's frame;
* ``ground_truth`` (nav_msgs/Odometry) and ``truth/map -> truth/base_footprint`` on ``tf``: the
  simulator's GroundTruth sensor, a tree of its own that never meets SLAM's map;
* ``tf_static``: base_footprint -> base_link and every sensor mount; ``robot_description``
  (ROS 2: transient local; ROS 1: the parameter); ``/clock`` from the STA lines with
  ``use_sim_time``.

The scan, odometry and truth are published on the connection's reader thread as each line
arrives. UDK's P3AT sends no wheel state, so ``joint_states`` is not published (said at start).
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass

import numpy as np

from usar_arm.core.errors import InvalidInputError
from usar_arm.core.platform import FRAME_STYLES, PlatformDescription, PlatformFrames, mount_matrix
from usar_arm.core.spatial import invert, transform
from usar_arm.description.platform import LivePlatform
from usar_arm.ros.drive import (
    DriveCommand,
    WheelCommand,
    drive_line,
    stop_command,
    velocity_command,
)
from usar_arm.ros.frames import Edge
from usar_arm.ros.platform_state import PoseSample, PoseTracker, scan_fields, sensor_pose
from usar_arm.ros.transport import (
    ClockRecord,
    Counted,
    Kind,
    OdometryRecord,
    Publisher,
    ScanRecord,
    TfRecord,
    Transport,
    TwistRecord,
    summary,
)
from usar_arm.urdf.description_reader import read_urdf
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.inbox import Received

log = logging.getLogger("usar_arm.ros")

TRUTH_PREFIX = "truth/"
CLAMP_LOG_S = 2.0
"""At most one clamping log line per this many seconds."""


@dataclass(frozen=True)
class PlatformNodeOptions:
    """The command line's settings; each is also a ROS parameter (same name).

    Attributes:
        robot_type: vehicle class. host, port: a USARSim server ('' = embedded, ``rooms``).
        start: start pose ('' = the server's first). use_sim_time: stamps and /clock from the
        simulator. frames: ``rep105`` or ``seed`` (the 2012 names). odom_sensor: the sensor
        odom comes from ('' = the first INS, else the first Odometry). cmd_timeout: s without
        cmd_vel after which the robot is stopped. wire_precision: the embedded simulator's.
    """

    robot_type: str = "P3AT"
    host: str = ""
    port: int = 3000
    start: str = ""
    use_sim_time: bool = False
    frames: str = "rep105"
    odom_sensor: str = ""
    cmd_timeout: float = 0.5
    wire_precision: str = "udk"
    node_name: str = "usar_arm"


def odom_source(desc: PlatformDescription, asked: str) -> str:
    """The name of the sensor odom comes from: ``asked``, else the first INS, else the first
    Odometry. Raises InvalidInputError naming the pose sensors when there is none."""
    poses = [s for s in desc.sensors if s.type.lower() in ("ins", "odometry")]
    if asked:
        for s in poses:
            if s.name.lower() == asked.lower():
                return s.name
        raise InvalidInputError(f"odom_sensor '{asked}' is not a pose sensor of {desc.name}; "
                                f"it has: {', '.join(s.name for s in poses) or 'none'}")
    for kind in ("ins", "odometry"):
        for s in poses:
            if s.type.lower() == kind:
                return s.name
    raise InvalidInputError(f"{desc.name} has no INS or Odometry sensor to give odom")


class Streams:
    """Publishes scan, odom, ground truth, tf and /clock from the SEN and STA lines."""

    def __init__(self, transport: Transport, desc: PlatformDescription, frames: PlatformFrames,
                 odom_sensor: str, counts: dict[str, int]):
        self.transport, self.desc, self.frames = transport, desc, frames
        self.use_sim_time = transport.use_sim_time
        footprint = transform(pos=(0.0, 0.0, desc.footprint_height)) \
            if frames.footprint is not None else np.eye(4)
        # base_footprint in a sensor's frame: mount^-1 (base_link in the sensor) times
        # base_link -> base_footprint (down by the footprint height).
        self.odom_name = odom_sensor
        odom = desc.sensor(odom_sensor)
        to_root = invert(mount_matrix(odom)) @ invert(footprint) \
            if odom.type.lower() == "ins" else np.eye(4)
        self.odom = PoseTracker(to_root, relative=True)
        truth = desc.sensors_of("GroundTruth")
        self.truth_name = truth[0].name if truth else None
        self.truth = PoseTracker(invert(mount_matrix(truth[0])) @ invert(footprint)
                                 if truth else np.eye(4), relative=False)
        self.scanners = {s.name.lower(): s for s in desc.sensors_of("RangeScanner")}
        self.scan_times: dict[str, float] = {}
        def publisher(topic: str, kind: Kind, depth: int) -> Counted:
            return Counted(transport.publisher(topic, kind, depth), topic, counts)

        self.clock = publisher("/clock", Kind.CLOCK, 10) if self.use_sim_time else None
        self.scan_pub = publisher("scan", Kind.SCAN, 10)
        self.odom_pub = publisher("odom", Kind.ODOMETRY, 10)
        self.truth_pub = publisher("ground_truth", Kind.ODOMETRY, 10)
        self.tf = publisher("tf", Kind.TF, 100)
        self.sim_time = 0.0
        self.counts = counts
        self.failures: set[str] = set()

    def on_line(self, rec: Received) -> None:
        """The connection's subscriber (its reader thread); never raises: a failure is logged
        as a warning the first time of its kind (a context shutting down: at debug level)."""
        try:
            self._handle(rec)
        except Exception as exc:  # a publisher of a context shutting down, a bad number
            kind = type(exc).__name__
            quiet = kind in self.failures or not self.transport.ok()
            self.failures.add(kind)
            log.log(logging.DEBUG if quiet else logging.WARNING,
                    "%s line not published: %s: %s", rec.line[:40], kind, exc)

    def _stamp(self, rec: Received, sim: float | None) -> float:
        """The stamp of a line's messages (s): its simulated time with use_sim_time (the last
        STA's when the line has none), else its arrival on the system clock."""
        if self.use_sim_time:
            return sim if sim is not None else self.sim_time
        return time.time() - (time.monotonic() - rec.wall_time)

    def _handle(self, rec: Received) -> None:
        msg = rec.message
        if isinstance(msg, m.Sta):
            self.sim_time = msg.time
            if self.clock is not None:
                self.clock.publish(ClockRecord(msg.time))
            return
        if isinstance(msg, m.RangeScan):
            self._scan(rec, msg)
            return
        name = getattr(msg, "name", "")
        if not isinstance(name, str):
            return
        at = getattr(msg, "time", None)
        if name.lower() == self.odom_name.lower():
            pose = sensor_pose(msg)
            if pose is not None:
                sample = self.odom.update(at if at is not None else rec.wall_time, pose)
                self._publish_pose(self.odom_pub, sample, self.frames.odom,
                                   self.frames.root, self._stamp(rec, at))
        elif self.truth_name is not None and name.lower() == self.truth_name.lower():
            pose = sensor_pose(msg)
            if pose is not None:
                sample = self.truth.update(at if at is not None else rec.wall_time, pose)
                self._publish_pose(self.truth_pub, sample,
                                   TRUTH_PREFIX + self.frames.map,
                                   TRUTH_PREFIX + self.frames.root, self._stamp(rec, at))

    def _scan(self, rec: Received, msg: m.RangeScan) -> None:
        sensor = self.scanners.get(msg.name.lower())
        if sensor is None or sensor.scanner is None:
            return
        now = msg.time if msg.time is not None else rec.wall_time
        last = self.scan_times.get(sensor.name, now)
        self.scan_times[sensor.name] = now
        fields = scan_fields(msg, sensor.scanner, now - last)
        self.scan_pub.publish(ScanRecord(self._stamp(rec, msg.time), self.frames.sensor(sensor),
                                         fields))

    def _publish_pose(self, pub: Publisher, sample: PoseSample, parent: str, child: str,
                      stamp: float) -> None:
        pub.publish(OdometryRecord(stamp, parent, child, sample))
        self.tf.publish(TfRecord(stamp, (Edge(parent, child, sample.pose),)))


class Driver:
    """cmd_vel -> DRIVE, with the command timeout (checked by a 20 Hz timer); the mapping by
    the vehicle's steering type (:func:`~usar_arm.ros.drive.velocity_command`)."""

    def __init__(self, transport: Transport, client: UsarClient, desc: PlatformDescription,
                 timeout: float):
        self.client, self.desc, self.timeout = client, desc, timeout
        self.last_command = time.monotonic()
        self.current: DriveCommand = stop_command(desc, WheelCommand(0.0, 0.0))
        self.last_clamp_log = -CLAMP_LOG_S
        self.lock = threading.Lock()
        transport.subscribe("cmd_vel", Kind.TWIST, self.on_twist)
        transport.timer(0.05, self.check_timeout)

    def send(self, command: DriveCommand) -> None:
        """One DRIVE line (rad/s and rad, not normalized)."""
        with self.lock:
            self.current = command
            self.client.send(drive_line(command))

    def on_twist(self, msg: TwistRecord) -> None:
        """A cmd_vel message: drive, or stop on a command that is not finite."""
        self.last_command = time.monotonic()
        d = self.desc
        try:
            command = velocity_command(d, msg.linear_x, msg.angular_z, self.current)
        except InvalidInputError as exc:
            log.error("cmd_vel refused, the robot stops: %s", exc)
            self.send_safely(stop_command(d, self.current))
            return
        if time.monotonic() - self.last_clamp_log > CLAMP_LOG_S and self._say(command):
            self.last_clamp_log = time.monotonic()
        self.send_safely(command)

    def _say(self, command: DriveCommand) -> bool:
        """Log what of a command had to give way (True when something did)."""
        d = self.desc
        if isinstance(command, WheelCommand):
            if command.clamped:
                log.info("cmd_vel clamped: wheels %.3f, %.3f rad/s asked, beyond the limit %g "
                         "rad/s; both scaled by %.3f (same direction and turn radius)",
                         *command.asked, d.max_speed, command.scale)
            return command.clamped
        if command.turn_refused:
            log.info("cmd_vel turns on the spot: an Ackermann vehicle cannot; it stands still, "
                     "steer kept at %.3f rad", command.steer)
        elif command.speed_clamped or command.steer_clamped:
            log.info("cmd_vel clamped: wheel spin %.3f rad/s (limit %g), steer %.3f rad (limit "
                     "%g)", command.speed, d.max_speed, command.steer, d.max_front_steer)
        return command.turn_refused or command.speed_clamped or command.steer_clamped

    def check_timeout(self) -> None:
        """Stop the robot when no cmd_vel came within the timeout."""
        if self.current.moving and time.monotonic() - self.last_command > self.timeout:
            log.info("no cmd_vel for %g s: the robot stops", self.timeout)
            self.send_safely(stop_command(self.desc, self.current))

    def send_safely(self, command: DriveCommand) -> None:
        try:
            self.send(command)
        except Exception as exc:  # the connection is gone: nothing to drive
            log.warning("DRIVE not sent: %s", exc)


def static_edges(desc: PlatformDescription, frames: PlatformFrames) -> list[Edge]:
    """base_footprint -> base_link and base_link -> every placed sensor (4x4, m)."""
    edges = []
    if frames.footprint is not None:
        edges.append(Edge(frames.footprint, frames.base,
                          transform(pos=(0.0, 0.0, desc.footprint_height))))
    edges += [Edge(frames.base, frames.sensor(s), mount_matrix(s)) for s in desc.sensors
              if frames.placed(s)]
    return edges


def resting_joints(urdf: str) -> list[Edge]:
    """Each moving joint of the vehicle's URDF (the wheels, an Ackermann's steering) at rest,
    its parent -> child transform at 0: UDK sends no wheel or steer state, so they are drawn
    where they are mounted, not turning (without them RViz's RobotModel has no transform for
    the wheel links and reports an error)."""
    return [Edge(j.parent, j.child, j.origin.matrix()) for j in read_urdf(urdf).chain.joints
            if j.actuated]


def serve(transport: Transport, live: LivePlatform, options: PlatformNodeOptions,
          frames: PlatformFrames, stop: threading.Event) -> int:
    """Publish and serve until ``stop`` is set or the middleware shuts down; the robot stops."""
    desc = live.result.description
    counts: dict[str, int] = {}
    streams = Streams(transport, desc, frames, odom_source(desc, options.odom_sensor), counts)
    driver = Driver(transport, live.client, desc, options.cmd_timeout)
    unsubscribe = live.client.subscribe(streams.on_line)
    static = Counted(transport.publisher("tf_static", Kind.TF, latched=True), "tf_static",
                     counts)
    static.publish(TfRecord(transport.now(), (*static_edges(desc, frames),
                                              *resting_joints(live.result.urdf))))
    transport.describe("robot_description", live.result.urdf)
    log.info("the server sends no wheel state (UDK's %s has no wheel encoder line): "
             "joint_states is not published", desc.name)
    log.info("serving %s on %s: cmd_vel, odom (from %s), scan, ground_truth, tf", desc.name,
             transport.name, streams.odom_name)
    try:
        transport.spin_until(stop)
    finally:
        unsubscribe()
        driver.send_safely(stop_command(desc, driver.current))
        log.info("published: %s", summary(counts))
    return 0


def run(transport: Transport, options: PlatformNodeOptions, stop: threading.Event) -> int:
    """Spawn and learn the vehicle its options (as the node's parameters have them) name,
    serve it until ``stop`` or Ctrl-C/SIGTERM; 0 on a clean stop (the vehicle stopped)."""
    chosen = transport.parameters(options)
    if chosen.frames not in FRAME_STYLES:
        raise InvalidInputError(f"frames '{chosen.frames}': expected one of "
                                f"{', '.join(FRAME_STYLES)}")
    frames = FRAME_STYLES[chosen.frames]
    live = LivePlatform(chosen.robot_type, chosen.host or None, chosen.port,
                        chosen.start or None, wire_precision=chosen.wire_precision,
                        frames=frames)
    try:
        return serve(transport, live, chosen, frames, stop)
    finally:
        live.close()
