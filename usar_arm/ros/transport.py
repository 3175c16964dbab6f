"""What a node's logic asks of a middleware, as plain data: the records it publishes, the kinds
of topic, and the one protocol each middleware's transport module implements.

The node logic (:mod:`.node` for an arm, :mod:`.platform_node` for a ground vehicle) decides
everything a client sees: what is published, when, with which stamp and which values, how a
goal is checked and run. A transport (:mod:`.ros2` on rclpy, :mod:`.ros1` on rospy) only turns
these records into its middleware's messages and back, and follows its middleware's own
conventions where they differ (ROS 1 keeps ``robot_description`` on the parameter server and
rejects a goal that fails its checks; ROS 2 publishes it on a transient-local topic and aborts
such a goal after accepting it). No middleware is imported here. Units: s, m, rad.
"""

from __future__ import annotations

import enum
import math
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar

from usar_arm.ros.frames import Edge
from usar_arm.ros.platform_state import PoseSample, ScanFields
from usar_arm.ros.runner import Outcome


class ActionKind(enum.Enum):
    """An action a node serves, by its ROS name (control_msgs on both middlewares). Adding one
    is a member here, its conversions in :mod:`usar_arm.ros.convert` and its classes in each
    transport's message table."""

    FOLLOW_JOINT_TRAJECTORY = "control_msgs/FollowJointTrajectory"
    GRIPPER_COMMAND = "control_msgs/GripperCommand"


class Kind(enum.Enum):
    """The message type of a topic, by its ROS name (the same on both middlewares)."""

    TEXT = "std_msgs/String"
    JOINT_STATE = "sensor_msgs/JointState"
    TF = "tf2_msgs/TFMessage"
    CLOCK = "rosgraph_msgs/Clock"
    SCAN = "sensor_msgs/LaserScan"
    ODOMETRY = "nav_msgs/Odometry"
    TWIST = "geometry_msgs/Twist"
    TRAJECTORY = "trajectory_msgs/JointTrajectory"
    EFFECTOR_COMMAND = "usarsim_inf/EffectorCommand"
    EFFECTOR_STATUS = "usarsim_inf/EffectorStatus"
    TOOLCHANGER_STATUS = "usarsim_inf/ToolchangerStatus"


def split_seconds(seconds: float) -> tuple[int, int]:
    """(whole seconds, nanoseconds) of a time in seconds, as both middlewares stamp it."""
    sec = math.floor(seconds)
    return int(sec), min(999_999_999, round((seconds - sec) * 1e9))


def seconds_of(sec: int, nanosec: int) -> float:
    """Seconds of a (sec, nanosec) stamp or duration, as both middlewares read one."""
    return float(sec) + float(nanosec) * 1e-9


@dataclass(frozen=True)
class JointStateRecord:
    """One sensor_msgs/JointState: ``stamp`` (s), URDF joint names, positions (rad or m) and
    velocities (rad/s or m/s; empty when unknown)."""

    stamp: float
    names: tuple[str, ...]
    position: tuple[float, ...]
    velocity: tuple[float, ...] = ()


@dataclass(frozen=True)
class TfRecord:
    """One tf2_msgs/TFMessage: every edge stamped with ``stamp`` (s)."""

    stamp: float
    edges: tuple[Edge, ...]


@dataclass(frozen=True)
class ClockRecord:
    """One rosgraph_msgs/Clock: the simulated ``time`` (s)."""

    time: float


@dataclass(frozen=True)
class ScanRecord:
    """One sensor_msgs/LaserScan in ``frame``, stamped ``stamp`` (s)."""

    stamp: float
    frame: str
    fields: ScanFields


@dataclass(frozen=True)
class OdometryRecord:
    """One nav_msgs/Odometry: ``child`` in ``parent`` with its twist, stamped ``stamp`` (s)."""

    stamp: float
    parent: str
    child: str
    sample: PoseSample


@dataclass(frozen=True)
class FeedbackRecord:
    """One FollowJointTrajectory feedback: desired positions and velocities, actual positions
    and their error (desired - actual), in the order of ``names``; ``stamp`` (s)."""

    stamp: float
    names: tuple[str, ...]
    desired: tuple[float, ...]
    velocity: tuple[float, ...]
    actual: tuple[float, ...]
    error: tuple[float, ...]


@dataclass(frozen=True)
class TwistRecord:
    """What a node reads of a geometry_msgs/Twist: ``linear_x`` (m/s), ``angular_z``
    (rad/s)."""

    linear_x: float
    angular_z: float


@dataclass(frozen=True)
class EffectorStatusRecord:
    """One usarsim_inf/EffectorStatus: effector ``name`` (the header's frame_id) in ``state``
    (0 OPEN, 1 CLOSE), stamped ``stamp`` (s)."""

    stamp: float
    name: str
    state: int


@dataclass(frozen=True)
class ToolchangerStatusRecord:
    """One usarsim_inf/ToolchangerStatus: tool changer ``name`` in ``state`` (0 OPEN, 1
    CLOSE), the tool's ``tool_type`` (usarsim_inf/ToolType: 0 UNKNOWN, 1 GRIPPER, 2 VACUUM, 3
    TOOLCHANGER) and ``tool_name``, stamped ``stamp`` (s)."""

    stamp: float
    name: str
    state: int
    tool_type: int
    tool_name: str


@dataclass(frozen=True)
class EffectorCommandRecord:
    """What a node reads of a usarsim_inf/EffectorCommand: ``state`` (0 OPEN, else CLOSE)."""

    state: int


@dataclass(frozen=True)
class GripperGoal:
    """A control_msgs GripperCommand goal: the gripper's target ``position`` (for a vacuum,
    its virtual joint: 0 off, 1 on) and ``max_effort`` (N; not used by a vacuum)."""

    position: float
    max_effort: float


@dataclass(frozen=True)
class GripperRecord:
    """A GripperCommand feedback or result: ``position`` (the virtual joint: 0 off, 1 on),
    ``effort`` (N; 0, not measured), ``stalled`` (a vacuum: it holds an object, by the
    simulator's GripTruth extension), ``reached_goal`` (its EFF status is the goal's)."""

    position: float
    effort: float
    stalled: bool
    reached_goal: bool


class GoalHandle(Protocol):
    """One goal of an action as the logic serves it; each transport wraps its middleware's goal
    handle in one."""

    goal: Any
    """Its :class:`ActionKind`'s goal record (a :class:`~usar_arm.ros.goals.TrajectoryGoal`, a
    :class:`GripperGoal`)."""
    ticket: int
    """Its place in the order goals arrived (the logic numbers it on arrival)."""

    def cancel_requested(self) -> bool:
        """Whether the client asked to cancel the goal."""

    def accept(self) -> None:
        """The goal passed its checks and starts."""

    def refuse(self, code: int, message: str) -> None:
        """The goal failed its checks (``code``: the controller's error code)."""

    def feedback(self, record: FeedbackRecord | GripperRecord) -> None:
        """Send one feedback message."""

    def finish(self, outcome: Outcome) -> None:
        """The goal ended as ``outcome`` says."""


class Publisher(Protocol):
    """A topic's publisher: takes the record of its :class:`Kind`."""

    def publish(self, record: Any) -> None:
        """Publish one record (the transport converts it)."""


class Settings(Protocol):
    """What every node's options have (a frozen dataclass: each field a parameter)."""

    @property
    def node_name(self) -> str:
        """The node's name."""

    @property
    def use_sim_time(self) -> bool:
        """Whether stamps come from the simulator (/clock)."""


Options = TypeVar("Options", bound=Settings)


class Transport(Protocol):
    """One middleware, as the node logic uses it. Topic names are relative (a namespace moves
    them) unless they start with ``/``.

    Attributes:
        use_sim_time: whether the node's clock is the simulated one (from /clock).
        name: the middleware's name, for logs (``ROS 1``, ``ROS 2``).
        trajectory_topic: the trajectory controller's topic under its name (ROS 2's
            joint_trajectory_controller: ``joint_trajectory``; ROS 1's: ``command``).
    """

    use_sim_time: bool
    name: str
    trajectory_topic: str

    def parameters(self, options: Options) -> Options:
        """The options as the node's parameters override them."""

    def publisher(self, topic: str, kind: Kind, depth: int = 10,
                  latched: bool = False) -> Publisher:
        """A publisher of ``kind`` on ``topic``; ``latched``: late joiners get the last
        message."""

    def describe(self, name: str, text: str) -> None:
        """Make a description (URDF, SRDF) known under ``name``, the middleware's way."""

    def subscribe(self, topic: str, kind: Kind, callback: Callable[[Any], None],
                  long_running: bool = False) -> None:
        """Call ``callback`` with each message's record (:class:`TwistRecord`,
        :class:`EffectorCommandRecord`, or a :class:`~usar_arm.ros.goals.TrajectoryGoal` for
        :attr:`Kind.TRAJECTORY`); ``long_running``: the callback
        may block for a goal's duration while later messages still arrive."""

    def action(self, name: str, kind: ActionKind, arrived: Callable[[GoalHandle], None],
               serve: Callable[[GoalHandle], None]) -> None:
        """Serve the action ``name`` of ``kind``: ``arrived`` is called at once on each
        goal's arrival (it must return quickly), ``serve`` on a thread of its own that may
        block until the goal ends."""

    def timer(self, period: float, callback: Callable[[], None]) -> None:
        """Call ``callback`` every ``period`` s."""

    def now(self) -> float:
        """The node's clock (s; simulated with :attr:`use_sim_time`)."""

    def ok(self) -> bool:
        """False once the middleware is shutting down."""

    def spin_until(self, stop: threading.Event) -> None:
        """Deliver callbacks until ``stop`` is set or the middleware shuts down (Ctrl-C,
        SIGTERM)."""


class Counted:
    """A publisher that counts what it published (``counts[topic]``): the node logs the
    counts when it stops, so a recording can be checked against them."""

    def __init__(self, inner: Publisher, topic: str, counts: dict[str, int]):
        self.inner, self.topic, self.counts = inner, topic, counts
        counts.setdefault(topic, 0)

    def publish(self, record: Any) -> None:
        """Publish, then count."""
        self.inner.publish(record)
        self.counts[self.topic] += 1


def summary(counts: dict[str, int]) -> str:
    """The counts as one log line's text (``topic n, ...``, in creation order)."""
    return ", ".join(f"{topic} {n}" for topic, n in counts.items()) or "nothing"
