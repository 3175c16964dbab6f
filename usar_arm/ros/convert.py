"""Records to messages and messages to records, written once for both middlewares.

ROS 1's genpy messages and ROS 2's rosidl messages of these types have the same fields (a
JointState's ``name``/``position``/``velocity``, a TransformStamped's ``transform.rotation``,
...); only their times differ (``secs``/``nsecs`` in ROS 1, ``sec``/``nanosec`` in ROS 2).
So each transport passes its message classes and its time functions (:class:`MessageTypes`)
and the conversion is the same code: the two nodes' messages carry the same numbers by
construction. No middleware is imported here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usar_arm.ros.frames import quaternion
from usar_arm.ros.goals import TrajectoryGoal
from usar_arm.ros.transport import (
    ActionKind,
    ClockRecord,
    EffectorCommandRecord,
    EffectorStatusRecord,
    FeedbackRecord,
    GripperGoal,
    GripperRecord,
    JointStateRecord,
    Kind,
    OdometryRecord,
    ScanRecord,
    TfRecord,
    ToolchangerStatusRecord,
    TwistRecord,
)


@dataclass(frozen=True)
class ActionTypes:
    """One action's classes in one middleware: its ``result`` and ``feedback`` messages and
    what its server is made with (``action``)."""

    action: Any
    result: Any
    feedback: Any


@dataclass(frozen=True)
class MessageTypes:
    """One middleware's message classes and time conversions.

    Attributes:
        time: seconds -> the middleware's Time. seconds: a Time or Duration -> seconds.
        ranges: a scan's ranges -> what its LaserScan takes (float32 values).
        by_kind: the message class of each :class:`~usar_arm.ros.transport.Kind`.
        transform, point: TransformStamped and JointTrajectoryPoint.
        actions: each action's classes.
    """

    time: Callable[[float], Any]
    seconds: Callable[[Any], float]
    ranges: Callable[[tuple[float, ...]], Any]
    by_kind: dict[Kind, Any]
    transform: Any
    point: Any
    actions: dict[ActionKind, ActionTypes]


def to_message(record: Any, types: MessageTypes) -> Any:
    """The message of a record (JointState, TFMessage, Clock, LaserScan, Odometry, an
    effector's status)."""
    kinds = types.by_kind
    if isinstance(record, JointStateRecord):
        state = kinds[Kind.JOINT_STATE](name=list(record.names), position=list(record.position),
                                        velocity=list(record.velocity))
        state.header.stamp = types.time(record.stamp)
        return state
    if isinstance(record, TfRecord):
        stamp = types.time(record.stamp)
        return kinds[Kind.TF](transforms=[_transform(e.parent, e.child, e.matrix, stamp, types)
                                          for e in record.edges])
    if isinstance(record, ClockRecord):
        return kinds[Kind.CLOCK](clock=types.time(record.time))
    if isinstance(record, ScanRecord):
        f = record.fields
        out = kinds[Kind.SCAN](angle_min=f.angle_min, angle_max=f.angle_max,
                               angle_increment=f.angle_increment, time_increment=0.0,
                               scan_time=f.scan_time, range_min=f.range_min,
                               range_max=f.range_max, ranges=types.ranges(f.ranges))
        out.header.stamp, out.header.frame_id = types.time(record.stamp), record.frame
        return out
    if isinstance(record, OdometryRecord):
        return _odometry(record, types)
    if isinstance(record, EffectorStatusRecord):
        return _effector_status(kinds[Kind.EFFECTOR_STATUS](), record.stamp, record.name,
                                record.state, types)
    if isinstance(record, ToolchangerStatusRecord):
        out = kinds[Kind.TOOLCHANGER_STATUS](tool_name=record.tool_name)
        out.header.stamp, out.header.frame_id = types.time(record.stamp), record.name
        _effector_status(out.effector_status, record.stamp, record.name, record.state, types)
        out.tool_type.type = record.tool_type
        return out
    raise TypeError(f"no message for {type(record).__name__}")


def _transform(parent: str, child: str, matrix: Any, stamp: Any, types: MessageTypes) -> Any:
    msg = types.transform()
    msg.header.stamp, msg.header.frame_id, msg.child_frame_id = stamp, parent, child
    p = matrix[:3, 3]
    t = msg.transform.translation
    t.x, t.y, t.z = float(p[0]), float(p[1]), float(p[2])
    r = msg.transform.rotation
    r.x, r.y, r.z, r.w = quaternion(matrix[:3, :3])
    return msg


def _effector_status(msg: Any, stamp: float, name: str, state: int, types: MessageTypes
                     ) -> Any:
    msg.header.stamp, msg.header.frame_id, msg.state = types.time(stamp), name, state
    return msg


def _odometry(record: OdometryRecord, types: MessageTypes) -> Any:
    msg = types.by_kind[Kind.ODOMETRY](child_frame_id=record.child)
    msg.header.stamp, msg.header.frame_id = types.time(record.stamp), record.parent
    sample = record.sample
    pose = msg.pose.pose
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in sample.pose[:3, 3])
    q = pose.orientation
    q.x, q.y, q.z, q.w = quaternion(sample.pose[:3, :3])
    t = msg.twist.twist
    t.linear.x, t.linear.y, t.linear.z = sample.linear
    t.angular.x, t.angular.y, t.angular.z = sample.angular
    return msg


def goal_record(kind: ActionKind, request: Any, types: MessageTypes) -> Any:
    """The goal record of an action's request (a :class:`TrajectoryGoal`, a
    :class:`~usar_arm.ros.transport.GripperGoal`)."""
    if kind is ActionKind.FOLLOW_JOINT_TRAJECTORY:
        return goal_from_message(request.trajectory, types, list(request.path_tolerance),
                                 list(request.goal_tolerance),
                                 types.seconds(request.goal_time_tolerance))
    if kind is ActionKind.GRIPPER_COMMAND:
        return GripperGoal(float(request.command.position), float(request.command.max_effort))
    raise TypeError(f"no goal record for {kind.value}")


def result_message(kind: ActionKind, code: int, message: str, types: MessageTypes,
                   state: Any = None) -> Any:
    """An action's result: FollowJointTrajectory's error code and its message; GripperCommand's
    ``state`` (a :class:`~usar_arm.ros.transport.GripperRecord`; None: nothing reached)."""
    if kind is ActionKind.FOLLOW_JOINT_TRAJECTORY:
        return types.actions[kind].result(error_code=code, error_string=message)
    if kind is ActionKind.GRIPPER_COMMAND:
        return _gripper(types.actions[kind].result,
                        state if state is not None else GripperRecord(0.0, 0.0, False, False))
    raise TypeError(f"no result for {kind.value}")


def _gripper(cls: Any, state: GripperRecord) -> Any:
    return cls(position=float(state.position), effort=float(state.effort),
               stalled=bool(state.stalled), reached_goal=bool(state.reached_goal))


def feedback_message(kind: ActionKind, record: FeedbackRecord | GripperRecord,
                     types: MessageTypes) -> Any:
    """An action's feedback message (FollowJointTrajectory: desired, actual, error;
    GripperCommand: the gripper's state)."""
    if kind is ActionKind.GRIPPER_COMMAND and isinstance(record, GripperRecord):
        return _gripper(types.actions[kind].feedback, record)
    if kind is not ActionKind.FOLLOW_JOINT_TRAJECTORY or not isinstance(record, FeedbackRecord):
        raise TypeError(f"no feedback for {kind.value} from {type(record).__name__}")
    msg = types.actions[kind].feedback(joint_names=list(record.names))
    msg.header.stamp = types.time(record.stamp)
    msg.desired = types.point(positions=list(record.desired), velocities=list(record.velocity))
    msg.actual = types.point(positions=list(record.actual))
    msg.error = types.point(positions=list(record.error))
    return msg


def goal_from_message(trajectory: Any, types: MessageTypes, path: list[Any] | None = None,
                      final: list[Any] | None = None, time_tolerance: float = 0.0
                      ) -> TrajectoryGoal:
    """A JointTrajectory (and tolerances, control_msgs/JointTolerance) as plain data."""
    points = trajectory.points
    return TrajectoryGoal(
        tuple(trajectory.joint_names), tuple(types.seconds(p.time_from_start) for p in points),
        tuple(tuple(p.positions) for p in points), tuple(tuple(p.velocities) for p in points),
        tuple(tuple(p.accelerations) for p in points), types.seconds(trajectory.header.stamp),
        {t.name: float(t.position) for t in path or []},
        {t.name: float(t.position) for t in final or []}, time_tolerance)


def to_record(kind: Kind, msg: Any, types: MessageTypes) -> Any:
    """The record of an incoming message (a Twist, a JointTrajectory, an EffectorCommand)."""
    if kind is Kind.TWIST:
        return TwistRecord(msg.linear.x, msg.angular.z)
    if kind is Kind.EFFECTOR_COMMAND:
        return EffectorCommandRecord(int(msg.state))
    if kind is Kind.TRAJECTORY:
        return goal_from_message(msg, types)
    raise TypeError(f"no record for incoming {kind.value}")
