"""ROS 2 bag export: a planned (and optionally executed) motion as a rosbag2 folder, MCAP storage.

The bag replays with ``ros2 bag play <folder>`` and its ``.mcap`` file opens directly in Foxglove.
It is written with the pure-Python ``rosbags`` library, so no ROS install is needed. Topics (all
stamps in ns since the epoch; ``start_ns`` is the start of the trajectory):

==========================  =============================  ======================================
topic                       type                           content
==========================  =============================  ======================================
``/robot_description``      std_msgs/msg/String            the URDF, once at start; QoS
                                                           transient_local, reliable, depth 1
``/tf_static``              tf2_msgs/msg/TFMessage         once at start, transient_local:
                                                           ``world -> <root link>`` (identity)
                                                           and every fixed joint (parent ->
                                                           child = joint origin)
``/planned_trajectory``     trajectory_msgs/msg/           once at start: the plan resampled at
                            JointTrajectory                ``joint_state_rate`` (positions,
                                                           velocities, accelerations)
``/joint_states``           sensor_msgs/msg/JointState     the executed samples when given (no
                                                           velocities), else the plan sampled at
                                                           ``joint_state_rate``
``/planned/joint_states``   sensor_msgs/msg/JointState     only with executed samples: the plan
``/tf``                     tf2_msgs/msg/TFMessage         every movable joint (parent -> child,
                                                           our own forward kinematics) at
                                                           ``tf_rate``, from the same source as
                                                           ``/joint_states``: RViz and Foxglove
                                                           show the arm without
                                                           robot_state_publisher
==========================  =============================  ======================================

The output is deterministic: the same inputs give the same bytes (no wall clock is recorded).

Distro caveat: ``rosbags`` writes rosbag2 metadata version 8 or 9 (9 for jazzy and newer, 8
otherwise), and Humble's rosbag2 (metadata version 5) refuses newer metadata
(ros2/rosbag2#1895). On Humble, delete ``metadata.yaml`` and run ``ros2 bag reindex <folder>``;
the MCAP file itself is readable everywhere.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from rosbags.interfaces import (
    Connection,
    Qos,
    QosDurability,
    QosHistory,
    QosLiveliness,
    QosReliability,
    QosTime,
)
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

# ExecutedSamples (t: (m,) s since the trajectory's start, q: (m, n) in its joint order) is the
# executor's result type; re-exported here so that it passes straight into write_bag.
from usar_arm.control.trajectory import ExecutedSamples, Trajectory
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.fileio import exchange, remove_leftovers, temporary_prefix
from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array, quat_from_matrix

# distro -> (typestore, rosbag2 metadata version rosbags should write)
DISTROS: dict[str, tuple[Stores, Literal[8, 9]]] = {
    "humble": (Stores.ROS2_HUMBLE, 8),
    "iron": (Stores.ROS2_IRON, 8),
    "jazzy": (Stores.ROS2_JAZZY, 9),
    "kilted": (Stores.ROS2_KILTED, 9),
}
WORLD_FRAME = "world"
_NS = 10**9
_MAX_STAMP_NS = (2**31 - 1) * _NS  # builtin_interfaces/Time.sec is an int32


def _qos(durability: QosDurability, depth: int) -> Qos:
    zero = QosTime(0, 0)  # 0 = the RMW default (no deadline, infinite lifespan)
    return Qos(QosHistory.KEEP_LAST, depth, QosReliability.RELIABLE, durability, zero, zero,
               QosLiveliness.AUTOMATIC, zero, False)


LATCHED_QOS = _qos(QosDurability.TRANSIENT_LOCAL, 1)
"""What robot_state_publisher offers on /robot_description and /tf_static."""
STREAM_QOS = _qos(QosDurability.VOLATILE, 10)


@dataclass(frozen=True)
class BagSummary:
    """What :func:`write_bag` wrote.

    Attributes:
        path: the rosbag2 folder. topics: topic -> message count, in writing order.
        duration_s: last stamp minus ``start_ns`` (s). start_ns: first stamp (ns since epoch).
    """

    path: Path
    topics: dict[str, int]
    duration_s: float
    start_ns: int


@dataclass(frozen=True)
class _Samples:
    """Joint values on a time grid: offsets (ns from start), q (m, n), qd and qdd or None."""

    offsets: np.ndarray
    q: Array
    qd: Array | None = None
    qdd: Array | None = None


def _grid(end_ns: int, rate: float, begin_ns: int = 0) -> np.ndarray:
    """Offsets (ns) ``begin + k / rate`` up to ``end``, ending exactly at ``end``."""
    period = _NS / rate
    offsets = begin_ns + np.round(np.arange(int((end_ns - begin_ns) / period + 1e-6) + 1)
                                  * period).astype(np.int64)
    if end_ns - offsets[-1] >= 1000:  # more than 1 µs left: add the end itself
        return np.append(offsets, np.int64(end_ns))
    offsets[-1] = end_ns
    return offsets


def _planned(planned: Trajectory, rate: float) -> _Samples:
    """The plan at ``rate`` Hz: Hermite positions and velocities, linear accelerations."""
    offsets = _grid(round(planned.duration * _NS), rate)
    times = offsets / _NS
    q, qd = zip(*(planned.at(float(t)) for t in times), strict=True)
    qdd = np.column_stack([np.interp(times, planned.t, planned.qdd[:, j])
                           for j in range(planned.qdd.shape[1])])
    return _Samples(offsets, np.array(q), np.array(qd), qdd)


def _interpolated(src: _Samples, rate: float, planned: Trajectory | None) -> _Samples:
    """``src`` at ``rate`` Hz over its own time span (the plan's Hermite curve if given)."""
    if planned is not None:
        offsets = _grid(int(src.offsets[-1]), rate)
        return _Samples(offsets, np.array([planned.at(t / _NS)[0] for t in offsets]))
    offsets = _grid(int(src.offsets[-1]), rate, int(src.offsets[0]))
    q = np.column_stack([np.interp(offsets, src.offsets, src.q[:, j])
                         for j in range(src.q.shape[1])])
    return _Samples(offsets, q)


def _check(chain: KinematicChain, urdf: str, planned: Trajectory,
           executed: ExecutedSamples | None, start_ns: int, rates: dict[str, float],
           distro: str) -> None:
    if distro not in DISTROS:
        raise InvalidInputError(f"unknown ROS 2 distro '{distro}'; expected one of "
                                f"{', '.join(DISTROS)}")
    for name, rate in rates.items():
        if not (math.isfinite(rate) and rate > 0):
            raise InvalidInputError(f"{name} must be a positive number of Hz, got {rate}")
    if not isinstance(urdf, str) or not urdf.strip():
        raise InvalidInputError("the URDF text for /robot_description is empty")
    if sorted(planned.joint_names) != sorted(chain.joint_names):
        raise InvalidInputError(
            f"the trajectory's joints ({', '.join(planned.joint_names)}) are not the chain's "
            f"actuated joints ({', '.join(chain.joint_names)})")
    n = len(planned.joint_names)
    if planned.q.ndim != 2 or planned.q.shape[1] != n or not np.all(np.isfinite(planned.q)):
        raise InvalidInputError(f"the planned positions must be finite, shape (m, {n}); got "
                                f"shape {planned.q.shape}")
    span = planned.duration
    if executed is not None:
        t, q = np.asarray(executed.t, float), np.asarray(executed.q, float)
        if t.ndim != 1 or len(t) < 1 or q.shape != (len(t), n):
            raise InvalidInputError(f"executed samples need t of shape (m,) and q of shape "
                                    f"(m, {n}) (joints {', '.join(planned.joint_names)}); got "
                                    f"t {t.shape} and q {q.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q))):
            raise InvalidInputError("executed samples contain NaN or infinite values")
        if t[0] < 0 or np.any(np.diff(t) <= 0):
            raise InvalidInputError(f"executed sample times must be >= 0 s and increase; got "
                                    f"t[0] = {t[0]:g} s, smallest step "
                                    f"{np.diff(t).min() if len(t) > 1 else 0:g} s")
        span = max(span, float(t[-1]))
    if (not isinstance(start_ns, int | np.integer) or start_ns < 0
            or start_ns + span * _NS > _MAX_STAMP_NS):
        raise InvalidInputError(f"start_ns must be an integer number of ns since the epoch, "
                                f"ending before 2038 (Time.sec is int32); got {start_ns!r}")


def _check_target(target: Path, overwrite: bool) -> None:
    if target.name in ("", ".", ".."):
        raise InvalidInputError(f"'{target}' cannot be a bag folder: give a path that names the "
                                f"folder to create, like plans/pick_1")
    if not (target.exists() or target.is_symlink()):
        return
    if not overwrite:
        raise InvalidInputError(f"{target} exists already; not overwriting it (pass "
                                f"overwrite=True to replace it)")
    if target.is_symlink() or not target.is_dir() or (
            not (target / "metadata.yaml").exists() and any(target.iterdir())):
        raise InvalidInputError(f"{target} exists and is not a rosbag2 folder (no "
                                f"metadata.yaml): refusing to replace it even with "
                                f"overwrite=True")


class BagMessages:
    """Builds a bag's messages with one typestore (``types``: name -> message class)."""

    def __init__(self, distro: str, start_ns: int):
        self.store = get_typestore(DISTROS[distro][0])
        self.types = self.store.types
        self.start_ns = start_ns

    def header(self, offset_ns: int, frame: str = "") -> Any:
        stamp = self.start_ns + int(offset_ns)
        time = self.types["builtin_interfaces/msg/Time"](stamp // _NS, stamp % _NS)
        return self.types["std_msgs/msg/Header"](time, frame)

    def transform(self, offset_ns: int, parent: str, child: str, pose: Array) -> Any:
        types = self.types
        w, x, y, z = quat_from_matrix(pose[:3, :3])
        translation = types["geometry_msgs/msg/Vector3"](*(float(v) for v in pose[:3, 3]))
        rotation = types["geometry_msgs/msg/Quaternion"](float(x), float(y), float(z), float(w))
        return types["geometry_msgs/msg/TransformStamped"](
            self.header(offset_ns, parent), child,
            types["geometry_msgs/msg/Transform"](translation, rotation))

    def joint_state(self, names: list[str], offset_ns: int, q: Array, qd: Array | None) -> Any:
        empty = np.zeros(0)
        return self.types["sensor_msgs/msg/JointState"](
            self.header(offset_ns), names, np.asarray(q, float),
            empty if qd is None else np.asarray(qd, float), empty)

    def trajectory(self, names: list[str], src: _Samples) -> Any:
        point = self.types["trajectory_msgs/msg/JointTrajectoryPoint"]
        duration = self.types["builtin_interfaces/msg/Duration"]
        assert src.qd is not None and src.qdd is not None
        points = [point(src.q[k], src.qd[k], src.qdd[k], np.zeros(0),
                        duration(int(t) // _NS, int(t) % _NS))
                  for k, t in enumerate(src.offsets)]
        return self.types["trajectory_msgs/msg/JointTrajectory"](self.header(0), names, points)

    def tf(self, chain: KinematicChain, names: list[str], src: _Samples) -> list[Any]:
        message = self.types["tf2_msgs/msg/TFMessage"]
        moving = [(jt, jt.origin.matrix(), names.index(jt.name)) for jt in chain.actuated_joints]
        return [message([self.transform(t, jt.parent, jt.child, origin @ jt.motion(q[col]))
                         for jt, origin, col in moving])
                for t, q in zip(src.offsets, src.q, strict=True)]

    def tf_static(self, chain: KinematicChain) -> Any:
        transforms = [self.transform(0, WORLD_FRAME, chain.root, np.eye(4))]
        transforms += [self.transform(0, jt.parent, jt.child, jt.origin.matrix())
                       for jt in chain.joints if not jt.actuated]
        return self.types["tf2_msgs/msg/TFMessage"](transforms)


# topic -> (type, QoS); the order is the connection (and summary) order
TOPICS: dict[str, tuple[str, Qos]] = {
    "/robot_description": ("std_msgs/msg/String", LATCHED_QOS),
    "/tf_static": ("tf2_msgs/msg/TFMessage", LATCHED_QOS),
    "/planned_trajectory": ("trajectory_msgs/msg/JointTrajectory", STREAM_QOS),
    "/joint_states": ("sensor_msgs/msg/JointState", STREAM_QOS),
    "/planned/joint_states": ("sensor_msgs/msg/JointState", STREAM_QOS),
    "/tf": ("tf2_msgs/msg/TFMessage", STREAM_QOS),
}


def _messages(chain: KinematicChain, urdf: str, planned: Trajectory,
              executed: ExecutedSamples | None, build: BagMessages, joint_state_rate: float,
              tf_rate: float) -> dict[str, list[tuple[int, Any]]]:
    """topic -> [(offset ns, message)] for every topic the bag gets."""
    names = list(planned.joint_names)
    plan = _planned(planned, joint_state_rate)
    assert plan.qd is not None
    plan_states = [(int(t), build.joint_state(names, t, plan.q[k], plan.qd[k]))
                   for k, t in enumerate(plan.offsets)]
    out: dict[str, list[tuple[int, Any]]] = {
        "/robot_description": [(0, build.types["std_msgs/msg/String"](urdf))],
        "/tf_static": [(0, build.tf_static(chain))],
        "/planned_trajectory": [(0, build.trajectory(names, plan))],
    }
    if executed is None:
        out["/joint_states"] = plan_states
        tf_src = _interpolated(plan, tf_rate, planned)
    else:
        offsets = np.round(np.asarray(executed.t, float) * _NS).astype(np.int64)
        done = _Samples(offsets, np.asarray(executed.q, float))
        out["/joint_states"] = [(int(t), build.joint_state(names, t, done.q[k], None))
                                for k, t in enumerate(offsets)]
        out["/planned/joint_states"] = plan_states
        tf_src = _interpolated(done, tf_rate, None)
    out["/tf"] = [(int(t), m) for t, m in zip(tf_src.offsets, build.tf(chain, names, tf_src),
                                              strict=True)]
    return out


def _write(bag: Path, version: Literal[8, 9], build: BagMessages,
           messages: dict[str, list[tuple[int, Any]]], topics: dict[str, tuple[str, Qos]]
           ) -> None:
    """Write a new rosbag2 folder ``bag``: connections in message order, messages by stamp."""
    records: list[tuple[int, int, Connection, memoryview]] = []
    with Writer(bag, version=version, storage_plugin=StoragePlugin.MCAP) as writer:
        for order, (topic, stamped) in enumerate(messages.items()):
            msgtype, qos = topics[topic]
            conn = writer.add_connection(topic, msgtype, typestore=build.store,
                                         offered_qos_profiles=[qos])
            records += [(build.start_ns + t, order, conn,
                         build.store.serialize_cdr(msg, msgtype, little_endian=True))
                        for t, msg in stamped]
        records.sort(key=lambda r: (r[0], r[1]))
        for stamp, _, conn, data in records:
            writer.write(conn, stamp, data)


def _move_into_place(bag: Path, target: Path, staging: Path) -> None:
    """Rename ``bag`` to ``target``. A bag already there is swapped with the new one in one
    atomic step (the old one then lies in ``staging``, which the caller deletes), so ``target``
    always holds a complete bag; where the system cannot swap folders, the old bag is moved
    aside first (a kill between the two renames then leaves it in ``staging``)."""
    if target.exists() and exchange(bag, target):
        return
    old = staging / "replaced"
    if target.exists():
        os.rename(target, old)
    try:
        os.rename(bag, target)
    except BaseException:
        if old.exists():
            os.rename(old, target)
        raise


def write_bag(path: str | Path, chain: KinematicChain, urdf: str, planned: Trajectory,
              executed: ExecutedSamples | None = None, *, start_ns: int = 1_700_000_000 * _NS,
              joint_state_rate: float = 100.0, tf_rate: float = 50.0, overwrite: bool = False,
              distro: str = "humble") -> BagSummary:
    """Write a rosbag2 folder (MCAP storage) with the robot, its plan and its motion.

    Args:
        path: the bag folder to create (it gets ``metadata.yaml`` and ``<name>.mcap``).
        chain: the robot; its fixed joints go to /tf_static, its movable joints to /tf.
        urdf: the URDF text for /robot_description.
        planned: the planned trajectory (joint order: any permutation of the chain's).
        executed: measured joint values, if the plan was executed; /joint_states then carries
            them, and the plan goes to /planned/joint_states.
        start_ns: stamp (ns since the epoch) of the trajectory's start.
        joint_state_rate: Hz of the sampled plan (/joint_states, /planned_trajectory).
        tf_rate: Hz of /tf.
        overwrite: replace an existing bag at ``path``.
        distro: ROS 2 distro whose message definitions the bag carries (see ``DISTROS``).

    Raises:
        InvalidInputError: bad input, or ``path`` exists (and ``overwrite`` is False, or it is
            not a bag folder). A failure never leaves a partial bag at ``path``.
    """
    target = Path(path)
    _check(chain, urdf, planned, executed, start_ns,
           {"joint_state_rate": joint_state_rate, "tf_rate": tf_rate}, distro)
    _check_target(target, overwrite)
    build = BagMessages(distro, int(start_ns))
    messages = _messages(chain, urdf, planned, executed, build, joint_state_rate, tf_rate)
    return write_topics(target, TOPICS, messages, build, overwrite=overwrite, distro=distro)


def write_topics(target: Path, topics: dict[str, tuple[str, Qos]],
                 messages: dict[str, list[tuple[int, Any]]], build: BagMessages, *,
                 overwrite: bool, distro: str) -> BagSummary:
    """Write ``messages`` (topic -> [(offset ns from ``build.start_ns``, message)], topics in
    connection order; types and QoS from ``topics``) as a new rosbag2 folder (MCAP) at
    ``target``, atomically: a staging folder beside it, renamed into place.

    Raises:
        InvalidInputError: ``target`` exists (and ``overwrite`` is False, or it is no bag).
    """
    _check_target(target, overwrite)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_leftovers(target)  # staging folders of writers that were killed
    staging = Path(tempfile.mkdtemp(prefix=temporary_prefix(target), suffix=".tmp",
                                    dir=target.parent))
    try:
        bag = staging / target.name  # rosbags names the .mcap file after the folder
        _write(bag, DISTROS[distro][1], build, messages, topics)
        _check_target(target, overwrite)  # again: something may have appeared meanwhile
        _move_into_place(bag, target, staging)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    last = max((t for stamped in messages.values() for t, _ in stamped), default=0)
    return BagSummary(target, {topic: len(stamped) for topic, stamped in messages.items()},
                      last / _NS, int(build.start_ns))

__all__ = ["DISTROS", "LATCHED_QOS", "STREAM_QOS", "BagMessages", "BagSummary",
           "ExecutedSamples", "write_bag", "write_topics"]
