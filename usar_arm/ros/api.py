"""The one module of usar-arm that imports rclpy and the ROS 2 message packages.

The arm's node (:mod:`.node`) and the platform's (:mod:`.platform_node`) take every ROS name
from here, with the small conversions both need (times, transforms). The generated tf2_msgs,
control_msgs and nav_msgs come from the cache :mod:`usar_arm.ros.build` fills.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import threading
from collections.abc import Callable
from typing import Any, TypeVar

from usar_arm.ros.build import ensure_importable
from usar_arm.ros.frames import Edge, quaternion

ensure_importable()  # the generated packages below come from the cache

import rclpy  # noqa: E402
from builtin_interfaces.msg import Duration, Time  # noqa: E402
from control_msgs.action import FollowJointTrajectory  # noqa: E402
from geometry_msgs.msg import TransformStamped, Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.action import ActionServer, CancelResponse, GoalResponse  # noqa: E402
from rclpy.callback_groups import ReentrantCallbackGroup  # noqa: E402
from rclpy.executors import (  # noqa: E402
    Executor,
    ExternalShutdownException,
    MultiThreadedExecutor,
    SingleThreadedExecutor,
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

__all__ = ["LATCHED", "ActionServer", "CancelResponse", "Clock", "Duration", "EventsExecutor",
           "ExternalShutdownException", "FollowJointTrajectory", "GoalResponse", "JointState",
           "JointTrajectory", "JointTrajectoryPoint", "LaserScan", "MultiThreadedExecutor",
           "Node", "Odometry", "Parameter", "ReentrantCallbackGroup", "SingleThreadedExecutor",
           "String", "TFMessage",
           "Time", "TransformStamped", "Twist", "declared_options", "rclpy", "ros_seconds",
           "ros_time", "run_ros", "spin_until", "transform_message"]

log = logging.getLogger("usar_arm.ros")

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
"""robot_description and tf_static: late joiners get the last message."""


def ros_time(seconds: float) -> Time:
    """A builtin_interfaces/Time from seconds."""
    sec = math.floor(seconds)
    return Time(sec=int(sec), nanosec=min(999_999_999, round((seconds - sec) * 1e9)))


def ros_seconds(stamp: Time | Duration) -> float:
    """Seconds of a Time or Duration."""
    return float(stamp.sec) + float(stamp.nanosec) * 1e-9


def transform_message(edge: Edge, stamp: Time) -> TransformStamped:
    """One edge of a transform tree as a TransformStamped (m, quaternion)."""
    msg = TransformStamped()
    msg.header.stamp = stamp
    msg.header.frame_id = edge.parent
    msg.child_frame_id = edge.child
    p = edge.matrix[:3, 3]
    msg.transform.translation.x, msg.transform.translation.y = float(p[0]), float(p[1])
    msg.transform.translation.z = float(p[2])
    r = msg.transform.rotation
    r.x, r.y, r.z, r.w = quaternion(edge.matrix[:3, :3])
    return msg


Options = TypeVar("Options")


def declared_options(node: Node, options: Options) -> Options:
    """The options (a dataclass) as the node's parameters have them: each field (but
    ``node_name``) is declared as a parameter of the same name that ``--ros-args -p`` overrides;
    ``use_sim_time`` is ROS's own parameter."""
    values: dict[str, Any] = {}
    for field in dataclasses.fields(options):  # type: ignore[arg-type]
        if field.name in ("node_name", "use_sim_time"):
            continue
        values[field.name] = node.declare_parameter(
            field.name, getattr(options, field.name)).value
    values["use_sim_time"] = bool(node.get_parameter("use_sim_time").value)
    return dataclasses.replace(options, **values)  # type: ignore[type-var]


def run_ros(node_name: str, use_sim_time: bool, ros_args: list[str] | None,
            body: Callable[[Node], int]) -> int:
    """Start ROS with ``ros_args``, make the node, run ``body(node)`` and return its exit code;
    a Ctrl-C or SIGTERM while it starts is a clean stop (0). The node and the context are shut
    down after (``body`` closes what it opened)."""
    rclpy.init(args=["usar-arm", "--ros-args", *(ros_args or [])])
    node = Node(node_name, parameter_overrides=[
        Parameter("use_sim_time", value=True)] if use_sim_time else [])
    try:
        return body(node)
    except Exception:
        if not rclpy.ok():  # Ctrl-C/SIGTERM while starting: a clean stop
            log.info("stopped while starting")
            return 0
        raise
    finally:
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()


def spin_until(spin: Executor, stop: threading.Event) -> None:
    """Spin until ``stop`` is set or the context shuts down (Ctrl-C, SIGTERM; checked every
    0.1 s)."""
    try:
        while rclpy.ok() and not stop.is_set():
            spin.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
