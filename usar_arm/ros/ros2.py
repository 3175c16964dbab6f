"""The ROS 2 transport: the one module of usar-arm that imports rclpy and the ROS 2 message
packages.

It turns the node logic's records (:mod:`usar_arm.ros.transport`) into ROS 2 messages and
back. ROS 2's own conventions live here: ``robot_description`` is a reliable, transient-local
topic; a goal that fails its checks is accepted, then aborted with the controller's error code
(so the client gets the code in the result); a pre-empted goal is aborted. The generated
tf2_msgs, control_msgs and usarsim_inf come from the cache :mod:`usar_arm.ros.build` fills.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
from array import array
from collections.abc import Callable
from typing import Any

from usar_arm.ros.build import ensure_importable
from usar_arm.ros.convert import (
    ActionTypes,
    MessageTypes,
    feedback_message,
    goal_record,
    result_message,
    to_message,
    to_record,
)
from usar_arm.ros.transport import (
    ActionKind,
    FeedbackRecord,
    GoalHandle,
    GripperRecord,
    Kind,
    Options,
    seconds_of,
    split_seconds,
)

ensure_importable()  # the generated packages below come from the cache

import rclpy  # noqa: E402
from builtin_interfaces.msg import Duration, Time  # noqa: E402
from control_msgs.action import FollowJointTrajectory, GripperCommand  # noqa: E402
from geometry_msgs.msg import TransformStamped, Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.action import ActionServer, CancelResponse, GoalResponse  # noqa: E402
from rclpy.callback_groups import ReentrantCallbackGroup  # noqa: E402
from rclpy.executors import (  # noqa: E402
    Executor,
    ExternalShutdownException,
    MultiThreadedExecutor,
)
from rclpy.experimental import EventsExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from sensor_msgs.msg import JointState, LaserScan  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402
from usarsim_inf.msg import EffectorCommand, EffectorStatus, ToolchangerStatus  # noqa: E402

log = logging.getLogger("usar_arm.ros")

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
"""robot_description and tf_static: late joiners get the last message."""

RESULT_KEPT_S = 60
"""How long a finished goal's result is kept for a client to fetch (s; rclpy's default, 900 s,
lets the node's memory grow with every goal for 15 minutes)."""

def ros_time(seconds: float) -> Time:
    """A builtin_interfaces/Time from seconds."""
    sec, nanosec = split_seconds(seconds)
    return Time(sec=sec, nanosec=nanosec)


def ros_seconds(stamp: Time | Duration) -> float:
    """Seconds of a Time or Duration."""
    return seconds_of(stamp.sec, stamp.nanosec)


TYPES = MessageTypes(
    time=ros_time, seconds=ros_seconds, ranges=lambda r: array("f", r),  # no per-item checks
    by_kind={Kind.TEXT: String, Kind.JOINT_STATE: JointState, Kind.TF: TFMessage,
             Kind.CLOCK: Clock, Kind.SCAN: LaserScan, Kind.ODOMETRY: Odometry,
             Kind.TWIST: Twist, Kind.TRAJECTORY: JointTrajectory,
             Kind.EFFECTOR_COMMAND: EffectorCommand, Kind.EFFECTOR_STATUS: EffectorStatus,
             Kind.TOOLCHANGER_STATUS: ToolchangerStatus},
    transform=TransformStamped, point=JointTrajectoryPoint,
    actions={ActionKind.FOLLOW_JOINT_TRAJECTORY: ActionTypes(
        FollowJointTrajectory, FollowJointTrajectory.Result, FollowJointTrajectory.Feedback),
        ActionKind.GRIPPER_COMMAND: ActionTypes(
            GripperCommand, GripperCommand.Result, GripperCommand.Feedback)})
"""ROS 2's message classes for :mod:`usar_arm.ros.convert`."""


class Ros2Goal:
    """A goal handle of rclpy (an action of ``kind``) as the logic's
    :class:`~usar_arm.ros.transport.GoalHandle`; :attr:`result` is what the execute callback
    returns."""

    def __init__(self, handle: Any, kind: ActionKind):
        self.handle = handle
        self.kind = kind
        self.goal = goal_record(kind, handle.request, TYPES)
        self.ticket = 0
        self.result = TYPES.actions[kind].result()

    def cancel_requested(self) -> bool:
        """Whether the client asked to cancel."""
        return bool(self.handle.is_cancel_requested)

    def accept(self) -> None:
        """Nothing to say: ROS 2 goals are accepted on arrival."""

    def refuse(self, code: int, message: str) -> None:
        """Abort the (accepted) goal with the controller's error code."""
        self.result = result_message(self.kind, code, message, TYPES)
        self.handle.abort()

    def feedback(self, record: FeedbackRecord | GripperRecord) -> None:
        """Publish one feedback message."""
        self.handle.publish_feedback(feedback_message(self.kind, record, TYPES))

    def finish(self, outcome: Any) -> None:
        """Succeed, cancel or abort (a pre-empted goal too: ROS 2 has no PREEMPTED)."""
        self.result = result_message(self.kind, outcome.code, outcome.message, TYPES,
                                     outcome.state)
        if outcome.succeeded:
            self.handle.succeed()
        elif outcome.cancelled:
            self.handle.canceled()
        else:
            self.handle.abort()


class _Publisher:
    def __init__(self, inner: Any):
        self.inner = inner

    def publish(self, record: Any) -> None:
        self.inner.publish(to_message(record, TYPES))


class Ros2Transport:
    """The logic's :class:`~usar_arm.ros.transport.Transport` on an rclpy node. Callbacks that
    may block (goals) run on a multi-threaded executor; a node without any runs on rclpy's
    events executor (half the CPU of the single-threaded one, measured with the platform)."""

    name = "ROS 2"
    trajectory_topic = "joint_trajectory"

    def __init__(self, node: Node):
        self.node = node
        self.use_sim_time = bool(node.get_parameter("use_sim_time").value)
        self._kept: list[Any] = []  # latched publishers, subscriptions, servers: kept alive
        self._group = ReentrantCallbackGroup()
        self._concurrent = False
        self._goals: dict[bytes, Ros2Goal] = {}
        self._spin: Executor | None = None

    def parameters(self, options: Options) -> Options:
        """Each option (but ``node_name``) declared as a parameter of the same name, which
        ``--ros-args -p`` overrides; ``use_sim_time`` is ROS's own."""
        values: dict[str, Any] = {}
        for field in dataclasses.fields(options):  # type: ignore[arg-type]
            if field.name in ("node_name", "use_sim_time"):
                continue
            values[field.name] = self.node.declare_parameter(
                field.name, getattr(options, field.name)).value
        values["use_sim_time"] = self.use_sim_time
        return dataclasses.replace(options, **values)  # type: ignore[type-var]

    def publisher(self, topic: str, kind: Kind, depth: int = 10,
                  latched: bool = False) -> _Publisher:
        """A publisher of ``kind`` (reliable; transient local when ``latched``)."""
        return _Publisher(self.node.create_publisher(TYPES.by_kind[kind], topic,
                                                     LATCHED if latched else depth))

    def describe(self, name: str, text: str) -> None:
        """A transient-local std_msgs/String topic ``name``, as robot_state_publisher does."""
        publisher = self.node.create_publisher(String, name, LATCHED)
        publisher.publish(String(data=text))
        self._kept.append(publisher)

    def subscribe(self, topic: str, kind: Kind, callback: Callable[[Any], None],
                  long_running: bool = False) -> None:
        """A subscription converting each message to its record."""
        self._concurrent |= long_running
        self._kept.append(self.node.create_subscription(
            TYPES.by_kind[kind], topic, lambda msg: callback(to_record(kind, msg, TYPES)), 10,
            callback_group=self._group if long_running else None))

    def action(self, name: str, kind: ActionKind, arrived: Callable[[GoalHandle], None],
               serve: Callable[[GoalHandle], None]) -> None:
        """An rclpy action server: every goal accepted at once, then served."""
        self._concurrent = True

        def accepted(handle: Any) -> None:
            goal = Ros2Goal(handle, kind)
            arrived(goal)
            self._goals[bytes(handle.goal_id.uuid)] = goal
            handle.execute()

        def execute(handle: Any) -> Any:
            goal = self._goals.pop(bytes(handle.goal_id.uuid), None)
            if goal is None:  # executed without passing through accepted (not seen)
                goal = Ros2Goal(handle, kind)
                arrived(goal)
            serve(goal)
            return goal.result

        self._kept.append(ActionServer(
            self.node, TYPES.actions[kind].action, name, execute_callback=execute,
            goal_callback=lambda _goal: GoalResponse.ACCEPT, handle_accepted_callback=accepted,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT, callback_group=self._group,
            result_timeout=RESULT_KEPT_S))

    def timer(self, period: float, callback: Callable[[], None]) -> None:
        """An rclpy timer."""
        self._kept.append(self.node.create_timer(period, callback))

    def now(self) -> float:
        """The node's clock (s)."""
        return float(self.node.get_clock().now().nanoseconds) * 1e-9

    def ok(self) -> bool:
        """False once the context shuts down."""
        return bool(rclpy.ok())

    def spin_until(self, stop: threading.Event) -> None:
        """Spin until ``stop`` is set or the context shuts down (checked every 0.1 s)."""
        self._spin = MultiThreadedExecutor(num_threads=4) if self._concurrent \
            else EventsExecutor()
        self._spin.add_node(self.node)
        try:
            while rclpy.ok() and not stop.is_set():
                self._spin.spin_once(timeout_sec=0.1)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass

    def close(self) -> None:
        """Stop the executor (after the logic has stopped what it runs)."""
        if self._spin is not None:
            self._spin.shutdown(timeout_sec=2.0)


Body = Callable[[Ros2Transport, Options, threading.Event], int]


def run(options: Options, ros_args: list[str] | None, stop: threading.Event | None,
        body: Body[Options]) -> int:
    """Start ROS 2 with ``ros_args``, make the node (named ``options.node_name``), run
    ``body(transport, options, stop)`` and return its exit code; a Ctrl-C or SIGTERM while it
    starts is a clean stop (0)."""
    rclpy.init(args=["usar-arm", "--ros-args", *(ros_args or [])])
    use_sim_time = options.use_sim_time
    node = Node(options.node_name, parameter_overrides=[
        Parameter("use_sim_time", value=True)] if use_sim_time else [])
    transport = Ros2Transport(node)
    try:
        return body(transport, options, stop or threading.Event())
    except Exception:
        if not rclpy.ok():  # Ctrl-C/SIGTERM while starting: a clean stop
            log.info("stopped while starting")
            return 0
        raise
    finally:
        transport.close()
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
