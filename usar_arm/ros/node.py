"""The live ROS 2 node (``usar-arm ros``): the simulated arm as a ROS 2 robot.

Every ROS name comes from :mod:`usar_arm.ros.api` (the one module that imports rclpy and the
message packages). It serves:

* ``robot_description`` (std_msgs/String, reliable, transient local): the learnt URDF;
* ``joint_states`` (sensor_msgs/JointState): one per ASTA line, published on the line's
  arrival and stamped with it, URDF joint names, rad/m;
* ``tf_static`` / ``tf`` (tf2_msgs/TFMessage): world -> base_link, every fixed joint, every
  moving joint per ASTA (what robot_state_publisher does with the joint states);
* ``<controller>/follow_joint_trajectory`` (control_msgs/action/FollowJointTrajectory) and
  ``<controller>/joint_trajectory`` (trajectory_msgs/JointTrajectory): the two interfaces of
  joint_trajectory_controller, run by :class:`~usar_arm.ros.runner.GoalRunner`;
* ``/clock`` (rosgraph_msgs/Clock) from the ASTA lines' simulated time with ``use_sim_time``;
* ``robot_description_semantic`` (the SRDF, transient local) for MoveIt, and on ``tf`` the tip
  GroundTruth sensor's frame as the simulator reports it (``<sensor>_truth`` in base_link).

Names are relative, so ``--ros-args -r __ns:=/robot1`` moves all of them (``tf`` included)
under the namespace; ``frame_prefix`` prefixes the frame names for one shared tree.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from usar_arm import Arm
from usar_arm.core.errors import UsarArmError
from usar_arm.core.spatial import Array
from usar_arm.ros.api import (
    LATCHED,
    ActionServer,
    CancelResponse,
    Clock,
    FollowJointTrajectory,
    GoalResponse,
    JointState,
    JointTrajectory,
    JointTrajectoryPoint,
    MultiThreadedExecutor,
    Node,
    ReentrantCallbackGroup,
    String,
    TFMessage,
    declared_options,
    run_ros,
    spin_until,
)
from usar_arm.ros.api import ros_seconds as _seconds
from usar_arm.ros.api import ros_time as _time
from usar_arm.ros.api import transform_message as _transform
from usar_arm.ros.frames import Edge, TransformTree, world_from_platform
from usar_arm.ros.goals import GoalRejected, TrajectoryGoal, check_goal
from usar_arm.ros.runner import GoalRunner, Job, Outcome
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.inbox import Received

log = logging.getLogger("usar_arm.ros")

RESULT_KEPT_S = 60
"""How long a finished goal's result is kept for a client to fetch (s; rclpy's default, 900 s,
lets the node's memory grow with every goal for 15 minutes)."""


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
            embedded simulator (udk, full). node_name: the node's name.
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


def goal_from_message(trajectory: JointTrajectory, path: list[Any] | None = None,
                      final: list[Any] | None = None, time_tolerance: float = 0.0
                      ) -> TrajectoryGoal:
    """A JointTrajectory (and tolerances) as plain data."""
    points = trajectory.points
    return TrajectoryGoal(
        tuple(trajectory.joint_names), tuple(_seconds(p.time_from_start) for p in points),
        tuple(tuple(p.positions) for p in points), tuple(tuple(p.velocities) for p in points),
        tuple(tuple(p.accelerations) for p in points), _seconds(trajectory.header.stamp),
        {t.name: float(t.position) for t in path or []},
        {t.name: float(t.position) for t in final or []}, time_tolerance)


class StateStreams:
    """Publishes joint_states, tf and /clock from each ASTA line as it arrives (on the
    connection's reader thread)."""

    def __init__(self, node: Node, arm: Arm, tree: TransformTree, use_sim_time: bool):
        self.node = node
        self.names = list(arm.joint_names)
        self.links = arm.robot.wire_links
        self.actuator = str(arm.robot.actuator).lower()
        self.tree = tree
        self.use_sim_time = use_sim_time
        self.joint_states = node.create_publisher(JointState, "joint_states", 100)
        self.tf = node.create_publisher(TFMessage, "tf", 100)
        self.clock = node.create_publisher(Clock, "/clock", 10) if use_sim_time else None
        self.count = 0
        self._previous: tuple[float, Array] | None = None

    def on_line(self, rec: Received) -> None:
        """The connection's subscriber: act on this actuator's ASTA lines."""
        msg = rec.message
        if not isinstance(msg, m.Asta) or msg.name.lower() != self.actuator:
            return
        values = dict(msg.values)
        if not all(k in values for k in self.links):
            return
        q = np.array([values[k] for k in self.links])
        if not (np.all(np.isfinite(q)) and math.isfinite(msg.time)):
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
            self.clock.publish(Clock(clock=_time(sim_time)))
        stamp = _time(sim_time if self.use_sim_time else arrived)
        state = JointState(name=self.names, position=q.tolist())
        state.header.stamp = stamp
        if self._previous is not None and sim_time > self._previous[0]:
            state.velocity = ((q - self._previous[1]) / (sim_time - self._previous[0])).tolist()
        self._previous = (sim_time, q)
        self.joint_states.publish(state)
        self.tf.publish(TFMessage(transforms=[_transform(e, stamp)
                                              for e in self.tree.moving_edges(q)]))
        self.count += 1


class TipTruth:
    """Publishes the tip GroundTruth sensor's frame as the simulator reports it (child
    ``<tip sensor>_truth`` of base_link on ``tf``), from a thread reading its SEN lines."""

    def __init__(self, node: Node, arm: Arm, tree: TransformTree, streams: StateStreams):
        self.node = node
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
            stamp = _time(reading.time) if self.streams.use_sim_time \
                else self.node.get_clock().now().to_msg()
            edge = Edge(self.parent, self.child, reading.pose @ offset)
            try:
                self.streams.tf.publish(TFMessage(transforms=[_transform(edge, stamp)]))
            except Exception as exc:  # the context is shutting down
                log.debug("not published: %s", exc)
                return


class TrajectoryInterfaces:
    """The controller's action server and topic, on a :class:`GoalRunner`."""

    def __init__(self, node: Node, arm: Arm, runner: GoalRunner, controller: str,
                 rate_hz: float, scene: str = ""):
        self.node = node
        self.arm = arm
        self.world = arm.world(scene) if scene else None
        self.runner = runner
        self.rate_hz = rate_hz
        self.names = list(arm.joint_names)
        self._tickets: dict[bytes, int] = {}
        group = ReentrantCallbackGroup()
        self.server = ActionServer(
            node, FollowJointTrajectory, f"{controller}/follow_joint_trajectory",
            execute_callback=self._execute, goal_callback=lambda _goal: GoalResponse.ACCEPT,
            handle_accepted_callback=self._accepted,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT, callback_group=group,
            result_timeout=RESULT_KEPT_S)
        self.topic = node.create_subscription(JointTrajectory, f"{controller}/joint_trajectory",
                                              self._on_topic, 10, callback_group=group)

    def _accepted(self, handle: Any) -> None:
        """Number the goal in the order goals are accepted, then run it."""
        self._tickets[bytes(handle.goal_id.uuid)] = self.runner.ticket()
        handle.execute()

    def _current(self) -> Array:
        asta = self.arm.client.latest_asta(str(self.arm.robot.actuator)) \
            if self.arm.client is not None else None
        if asta is None:
            raise GoalRejected(-1, "no joint state from the simulator yet")
        values = dict(asta.values)
        return np.array([values[k] for k in self.arm.robot.wire_links])

    def _check(self, goal: TrajectoryGoal) -> Any:
        now = self.node.get_clock().now().nanoseconds * 1e-9
        checked = check_goal(goal, self.arm.robot.chain, self._current(), now, self.rate_hz)
        if self.world is not None:
            trajectory = checked.trajectory
            for i in range(0, len(trajectory.t), max(1, len(trajectory.t) // 200)):
                pairs = self.world.contacts(trajectory.q[i])
                if pairs:
                    raise GoalRejected(-1, f"the motion collides at t = {trajectory.t[i]:.2f}"
                                           f" s: {', '.join(f'{a}-{b}' for a, b in pairs)}")
        return checked

    def _execute(self, handle: Any) -> Any:
        ticket = self._tickets.pop(bytes(handle.goal_id.uuid), 0) or self.runner.ticket()
        request = handle.request
        result = FollowJointTrajectory.Result()
        try:
            goal = goal_from_message(request.trajectory, list(request.path_tolerance),
                                     list(request.goal_tolerance),
                                     _seconds(request.goal_time_tolerance))
            checked = self._check(goal)
        except GoalRejected as exc:
            log.warning("goal refused: %s", exc.message)
            result.error_code, result.error_string = exc.code, exc.message
            handle.abort()
            return result
        outcome = self.runner.run(Job(checked, lambda: bool(handle.is_cancel_requested),
                                      self._feedback_to(handle), "action goal", ticket))
        self._finish(handle, outcome)
        result.error_code, result.error_string = outcome.code, outcome.message
        return result

    def _finish(self, handle: Any, outcome: Outcome) -> None:
        log.info("goal %s: %s", "succeeded" if outcome.succeeded else
                 "cancelled" if outcome.cancelled else "aborted", outcome.message)
        try:
            if outcome.succeeded:
                handle.succeed()
            elif outcome.cancelled:
                handle.canceled()
            else:
                handle.abort()
        except Exception as exc:  # Ctrl-C/SIGTERM shut the context down first: nobody to tell
            log.debug("goal state not sent: %s", exc)

    def _feedback_to(self, handle: Any) -> Any:
        def send(desired: Array, velocity: Array, actual: Array) -> None:
            msg = FollowJointTrajectory.Feedback(joint_names=self.names)
            msg.header.stamp = self.node.get_clock().now().to_msg()
            msg.desired = JointTrajectoryPoint(positions=desired.tolist(),
                                               velocities=velocity.tolist())
            msg.actual = JointTrajectoryPoint(positions=actual.tolist())
            msg.error = JointTrajectoryPoint(positions=(desired - actual).tolist())
            handle.publish_feedback(msg)
        return send

    def _on_topic(self, msg: JointTrajectory) -> None:
        ticket = self.runner.ticket()
        if not msg.points:  # as joint_trajectory_controller: stop what runs and hold
            self.runner.stop_active("an empty joint_trajectory message: hold")
            log.info("joint_trajectory: an empty message; the arm holds")
            return
        try:
            checked = self._check(goal_from_message(msg))
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


def serve(node: Node, arm: Arm, options: NodeOptions, stop: threading.Event) -> int:
    """Publish and serve until ``stop`` is set or the ROS context shuts down (Ctrl-C,
    SIGTERM; checked every 0.1 s); the arm holds when it returns."""
    tree = TransformTree(arm.robot.chain, options.frame_prefix)
    assert arm.client is not None and arm.robot.actuator is not None
    executor = arm.executor()
    executor.identify()  # the drive model, once, before any goal (about 2 s)
    runner = GoalRunner(executor, arm.client, str(arm.robot.actuator), arm.robot.wire_links)
    streams = StateStreams(node, arm, tree, options.use_sim_time)
    unsubscribe = arm.client.subscribe(streams.on_line)
    controller = options.controller or f"{arm.robot.actuator}_controller"
    TrajectoryInterfaces(node, arm, runner, controller, options.rate_hz, options.scene)
    # Last: a client that has the description finds everything else served.
    static = node.create_publisher(TFMessage, "tf_static", LATCHED)
    stamp = node.get_clock().now().to_msg()
    static.publish(TFMessage(transforms=[_transform(e, stamp)
                                         for e in tree.static_edges(_world_from_root(arm))]))
    semantic = [text for name, text in arm.robot.files.items() if name.endswith(".srdf")]
    if semantic:
        srdf = node.create_publisher(String, "robot_description_semantic", LATCHED)
        srdf.publish(String(data=semantic[0]))
    truth = TipTruth(node, arm, tree, streams)
    description = node.create_publisher(String, "robot_description", LATCHED)
    description.publish(String(data=arm.urdf))
    spin = MultiThreadedExecutor(num_threads=4)
    spin.add_node(node)
    log.info("serving %s: %s/follow_joint_trajectory, joint_states, tf", arm.robot.actuator,
             controller)
    try:
        spin_until(spin, stop)
    finally:
        runner.stopping = "the node is shutting down"
        runner.stop_active("the node is shutting down")
        runner.wait_idle()  # the running goal, if any, has stopped and the arm holds
        truth.stop.set()
        if truth.thread.is_alive():
            truth.thread.join(2.0)
        unsubscribe()
        spin.shutdown(timeout_sec=2.0)
    return 0


def run(options: NodeOptions, ros_args: list[str] | None = None,
        stop: threading.Event | None = None) -> int:
    """Start ROS, learn the arm, serve until Ctrl-C/SIGTERM (or ``stop``); 0 on a clean
    stop (the arm holds)."""
    def body(node: Node) -> int:
        chosen = declared_options(node, options)
        arm = Arm.connect(chosen.robot_type, host=chosen.host or None, port=chosen.port,
                          start=chosen.start or None, wire_precision=chosen.wire_precision)
        try:
            return serve(node, arm, chosen, stop or threading.Event())
        finally:
            arm.close()

    return run_ros(options.node_name, options.use_sim_time, ros_args, body)
