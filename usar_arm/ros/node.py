"""The live node of an arm (``usar-arm ros``, ``usar-arm ros --ros1``): the simulated arm as a
ROS robot, written once for both middlewares (each a :class:`~usar_arm.ros.transport.Transport`:
:mod:`.ros2` on rclpy, :mod:`.ros1` on rospy). It serves:

* ``robot_description``: the learnt URDF (ROS 2: a transient-local topic; ROS 1: the parameter);
* ``joint_states`` (sensor_msgs/JointState): one per ASTA line, published on the line's
  arrival and stamped with it, URDF joint names, rad/m;
* ``tf_static`` / ``tf`` (tf2_msgs/TFMessage): world -> base_link, every fixed joint, every
  moving joint per ASTA (what robot_state_publisher does with the joint states);
* ``<controller>/follow_joint_trajectory`` (control_msgs FollowJointTrajectory) and
  ``<controller>/joint_trajectory`` (trajectory_msgs/JointTrajectory): the two interfaces of
  joint_trajectory_controller, run by :class:`~usar_arm.ros.runner.GoalRunner`;
* ``/clock`` (rosgraph_msgs/Clock) from the ASTA lines' simulated time with ``use_sim_time``;
* ``robot_description_semantic`` (the SRDF) for MoveIt, and on ``tf`` the tip GroundTruth
  sensor's frame as the simulator reports it (``<sensor>_truth`` in base_link);
* the effectors (:mod:`.effectors`): ``<name>/status`` and ``<name>/command`` (usarsim_inf)
  and ``<gripper>/gripper_cmd`` (control_msgs GripperCommand).

Names are relative, so a namespace moves all of them (``tf`` included); ``frame_prefix``
prefixes the frame names for one shared tree.
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass

import numpy as np

from usar_arm import Arm
from usar_arm.core.errors import UsarArmError
from usar_arm.core.spatial import Array
from usar_arm.ros.effectors import serve_effectors
from usar_arm.ros.frames import Edge, TransformTree, world_from_platform
from usar_arm.ros.goals import INVALID_GOAL, CheckedGoal, GoalRejected, TrajectoryGoal, check_goal
from usar_arm.ros.runner import Feedback, GoalRunner, Job, Outcome
from usar_arm.ros.transport import (
    ActionKind,
    ClockRecord,
    Counted,
    FeedbackRecord,
    GoalHandle,
    JointStateRecord,
    Kind,
    TfRecord,
    Transport,
    summary,
)
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.inbox import Received

log = logging.getLogger("usar_arm.ros")

@dataclass(frozen=True)
class NodeOptions:
    """The command line's settings; each is also a ROS parameter of the node (same name)
    that ``--ros-args -p name:=value`` overrides.

    Attributes:
        robot_type: robot class to spawn. host, port: a USARSim server ('' = embedded).
        start: the start pose name ('' = the server's first). controller: the trajectory
            controller's name ('' = ``<actuator>_controller``, what ``moveit-config`` writes).
        use_sim_time: stamps and /clock from the simulator's time. frame_prefix: prepended to
            every frame. rate_hz: the executor's command rate. scene: goals whose motion
            collides in it are refused ('' = none). wire_precision: number format of the
            embedded simulator (udk, full). node_name: the node's name (ROS 2: ``usar_arm``,
            ROS 1: ``RosSim``, the seed's). gripper_joint_states: also publish each
            gripper's virtual joint ``<gripper>_suction`` (0 off, 1 on) on joint_states, in
            a message of its own per EFF line (for MoveIt's gripper controller).
    """

    robot_type: str = "KR60"
    host: str = ""
    port: int = 3000
    start: str = ""
    controller: str = ""
    use_sim_time: bool = False
    frame_prefix: str = ""
    rate_hz: float = 100.0
    scene: str = ""
    wire_precision: str = "udk"
    node_name: str = "usar_arm"
    gripper_joint_states: bool = False


class StateStreams:
    """Publishes joint_states, tf and /clock from each ASTA line as it arrives (on the
    connection's reader thread)."""

    def __init__(self, transport: Transport, arm: Arm, tree: TransformTree,
                 counts: dict[str, int]):
        self.transport = transport
        self.names = tuple(arm.joint_names)
        self.links = arm.robot.wire_links
        self.actuator = str(arm.robot.actuator).lower()
        self.tree = tree
        self.use_sim_time = transport.use_sim_time
        self.clock = Counted(transport.publisher("/clock", Kind.CLOCK, 10), "/clock", counts) \
            if self.use_sim_time else None
        self.joint_states = Counted(transport.publisher("joint_states", Kind.JOINT_STATE, 100),
                                    "joint_states", counts)
        self.tf = Counted(transport.publisher("tf", Kind.TF, 100), "tf", counts)
        self.count = 0
        self._previous: tuple[float, Array] | None = None

    def on_line(self, rec: Received) -> None:
        """The connection's subscriber: act on this actuator's ASTA lines."""
        msg = rec.message
        if not isinstance(msg, m.Asta) or msg.name.lower() != self.actuator:
            return
        joints = msg.joints(self.links)
        if joints is None:
            return
        q = np.array(joints)
        if not (np.all(np.isfinite(q)) and np.isfinite(msg.time)):
            return
        try:
            # Stamped with the line's arrival (the system clock's reading of that moment).
            self.publish(q, float(msg.time), time.time() - (time.monotonic() - rec.wall_time))
        except Exception as exc:  # a publisher of a context shutting down: never kill the reader
            log.debug("not published: %s", exc)

    def publish(self, q: Array, sim_time: float, arrived: float) -> None:
        """One JointState, one TFMessage (and one Clock) for joint values ``q`` (rad/m),
        stamped with the simulated time (s) with use_sim_time, else ``arrived`` (s since the
        epoch)."""
        if self.clock is not None:
            self.clock.publish(ClockRecord(sim_time))
        stamp = sim_time if self.use_sim_time else arrived
        velocity: tuple[float, ...] = ()
        if self._previous is not None and sim_time > self._previous[0]:
            velocity = tuple(((q - self._previous[1]) / (sim_time - self._previous[0])).tolist())
        self._previous = (sim_time, q)
        self.joint_states.publish(JointStateRecord(stamp, self.names, tuple(q.tolist()),
                                                   velocity))
        self.tf.publish(TfRecord(stamp, tuple(self.tree.moving_edges(q))))
        self.count += 1


class TipTruth:
    """Publishes the tip GroundTruth sensor's frame as the simulator reports it (child
    ``<tip sensor>_truth`` of base_link on ``tf``), from a thread reading its SEN lines."""

    def __init__(self, transport: Transport, arm: Arm, tree: TransformTree,
                 streams: StateStreams):
        self.transport = transport
        self.sensor = arm.tip_sensor()
        self.parent = tree.frame(arm.robot.chain.root)
        self.child = tree.frame(f"{arm.robot.tip_sensor}_truth")
        self.streams = streams
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, name="tip-truth", daemon=True)
        if self.sensor is not None:
            self.thread.start()

    def _run(self) -> None:
        assert self.sensor is not None
        after: float | None = None
        offset = np.linalg.inv(self.sensor.sensor_to_tool0)
        while not self.stop.is_set():
            try:
                reading = self.sensor.read(after=after, timeout=1.0)
            except Exception as exc:  # the connection is gone: nothing more to publish
                log.warning("tip GroundTruth sensor: %s; its frame is no longer published", exc)
                return
            after = reading.time
            stamp = reading.time if self.streams.use_sim_time else self.transport.now()
            edge = Edge(self.parent, self.child, reading.pose @ offset)
            try:
                self.streams.tf.publish(TfRecord(stamp, (edge,)))
            except Exception as exc:  # the context is shutting down
                log.debug("not published: %s", exc)
                return


class TrajectoryInterfaces:
    """The controller's action and topic, on a :class:`GoalRunner`: what each goal is checked
    against, how it runs and how it ends (the transport says it the middleware's way)."""

    def __init__(self, transport: Transport, arm: Arm, runner: GoalRunner, controller: str,
                 rate_hz: float, scene: str = ""):
        self.transport = transport
        self.arm = arm
        self.world = arm.world(scene) if scene else None
        self.runner = runner
        self.rate_hz = rate_hz
        self.names = tuple(arm.joint_names)
        transport.action(f"{controller}/follow_joint_trajectory",
                         ActionKind.FOLLOW_JOINT_TRAJECTORY, self.arrived, self.serve)
        transport.subscribe(f"{controller}/{transport.trajectory_topic}", Kind.TRAJECTORY,
                            self._on_topic, long_running=True)

    def arrived(self, handle: GoalHandle) -> None:
        """Number the goal in the order goals arrive."""
        handle.ticket = self.runner.ticket()

    def _current(self) -> Array:
        asta = self.arm.client.latest_asta(str(self.arm.robot.actuator)) \
            if self.arm.client is not None else None
        joints = asta.joints(self.arm.robot.wire_links) if asta is not None else None
        if joints is None:
            raise GoalRejected(INVALID_GOAL, "no joint state from the simulator yet")
        return np.array(joints)

    def check(self, goal: TrajectoryGoal) -> CheckedGoal:
        """The goal checked against the arm where it is now (and the scene, if any).

        Raises:
            GoalRejected: a rule it breaks, with the controller's error code.
        """
        checked = check_goal(goal, self.arm.robot.chain, self._current(), self.transport.now(),
                             self.rate_hz)
        if self.world is not None:
            trajectory = checked.trajectory
            for i in range(0, len(trajectory.t), max(1, len(trajectory.t) // 200)):
                pairs = self.world.contacts(trajectory.q[i])
                if pairs:
                    raise GoalRejected(INVALID_GOAL, f"the motion collides at t = "
                                       f"{trajectory.t[i]:.2f} s: "
                                       f"{', '.join(f'{a}-{b}' for a, b in pairs)}")
        return checked

    def serve(self, handle: GoalHandle) -> None:
        """Check the goal, then run it to its end (blocks for the goal's duration)."""
        try:
            checked = self.check(handle.goal)
        except GoalRejected as exc:
            log.warning("goal refused: %s", exc.message)
            handle.refuse(exc.code, exc.message)
            return
        handle.accept()
        outcome = self.runner.run(Job(checked, handle.cancel_requested,
                                      self._feedback_to(handle), "action goal", handle.ticket))
        log.info("goal %s: %s", "succeeded" if outcome.succeeded else
                 "cancelled" if outcome.cancelled else "aborted", outcome.message)
        try:
            handle.finish(outcome)
        except Exception as exc:  # Ctrl-C/SIGTERM shut the middleware down first
            log.debug("goal state not sent: %s", exc)

    def _feedback_to(self, handle: GoalHandle) -> Feedback:
        def send(desired: Array, velocity: Array, actual: Array) -> None:
            handle.feedback(FeedbackRecord(
                self.transport.now(), self.names, tuple(desired.tolist()),
                tuple(velocity.tolist()), tuple(actual.tolist()),
                tuple((desired - actual).tolist())))
        return send

    def _on_topic(self, goal: TrajectoryGoal) -> None:
        ticket = self.runner.ticket()
        if not goal.positions:  # as joint_trajectory_controller: stop what runs and hold
            self.runner.stop_active("an empty joint_trajectory message: hold")
            log.info("joint_trajectory: an empty message; the arm holds")
            return
        try:
            checked = self.check(goal)
        except GoalRejected as exc:
            log.error("joint_trajectory message refused: %s", exc.message)
            return
        self._finish_topic(self.runner.run(Job(checked, lambda: False, lambda *_: None,
                                               "joint_trajectory message", ticket)))

    @staticmethod
    def _finish_topic(outcome: Outcome) -> None:
        log.info("joint_trajectory message: %s", outcome.message)


def _world_from_root(arm: Arm) -> Array:
    """Where the robot stands: its platform's GroundTruth pose (REP-103), else identity."""
    sensor = arm.tip_sensor()
    if sensor is None:
        return np.eye(4)
    try:
        sensor.read(timeout=2.0)
    except UsarArmError as exc:
        log.warning("no GroundTruth reading of the platform (%s): world -> base_link is the "
                    "identity", exc)
        return np.eye(4)
    return world_from_platform(sensor.platform_pose())


def serve(transport: Transport, arm: Arm, options: NodeOptions, stop: threading.Event) -> int:
    """Publish and serve until ``stop`` is set or the middleware shuts down (Ctrl-C,
    SIGTERM); the arm holds when it returns."""
    tree = TransformTree(arm.robot.chain, options.frame_prefix)
    assert arm.client is not None and arm.robot.actuator is not None
    executor = arm.executor()
    executor.identify()  # the drive model, once, before any goal (about 2 s)
    runner = GoalRunner(executor, arm.client, str(arm.robot.actuator), arm.robot.wire_links)
    counts: dict[str, int] = {}
    streams = StateStreams(transport, arm, tree, counts)
    unsubscribe = arm.client.subscribe(streams.on_line)
    controller = options.controller or f"{arm.robot.actuator}_controller"
    TrajectoryInterfaces(transport, arm, runner, controller, options.rate_hz, options.scene)
    effectors, _grippers = serve_effectors(
        transport, arm.client, arm.robot.files, counts,
        streams.joint_states if options.gripper_joint_states else None)
    unsubscribe_effectors = arm.client.subscribe(effectors.on_line)
    # Last: a client that has the description finds everything else served.
    static = Counted(transport.publisher("tf_static", Kind.TF, latched=True), "tf_static",
                     counts)
    static.publish(TfRecord(transport.now(), tuple(tree.static_edges(_world_from_root(arm)))))
    semantic = [text for name, text in arm.robot.files.items() if name.endswith(".srdf")]
    if semantic:
        transport.describe("robot_description_semantic", semantic[0])
    truth = TipTruth(transport, arm, tree, streams)
    transport.describe("robot_description", arm.urdf)
    log.info("serving %s on %s: %s/follow_joint_trajectory, joint_states, tf",
             arm.robot.actuator, transport.name, controller)
    try:
        transport.spin_until(stop)
    finally:
        runner.stopping = "the node is shutting down"
        runner.stop_active("the node is shutting down")
        runner.wait_idle()  # the running goal, if any, has stopped and the arm holds
        truth.stop.set()
        if truth.thread.is_alive():
            truth.thread.join(2.0)
        unsubscribe()
        unsubscribe_effectors()
        log.info("published: %s", summary(counts))
    return 0


def run(transport: Transport, options: NodeOptions, stop: threading.Event) -> int:
    """Learn the arm its options (as the node's parameters have them) name, serve it until
    ``stop`` or Ctrl-C/SIGTERM; 0 on a clean stop (the arm holds)."""
    chosen = transport.parameters(options)
    arm = Arm.connect(chosen.robot_type, host=chosen.host or None, port=chosen.port,
                      start=chosen.start or None, wire_precision=chosen.wire_precision)
    try:
        return serve(transport, arm, chosen, stop)
    finally:
        arm.close()
