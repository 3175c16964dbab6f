"""A real rclpy client (this process) of a `usar-arm ros` node (another process), each pair on
its own ROS_DOMAIN_ID and on localhost only."""

from __future__ import annotations

import contextlib
import fcntl
import itertools
import math
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from usar_arm.ros.build import ensure_importable

ensure_importable()

import rclpy  # noqa: E402
from control_msgs.action import FollowJointTrajectory  # noqa: E402
from control_msgs.msg import JointTolerance  # noqa: E402
from geometry_msgs.msg import Twist  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.action import ActionClient  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint  # noqa: E402

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
STARTUP_TIMEOUT_S = 120.0
_ids = itertools.count()


_leases: list[Any] = []


def domain_id() -> int:
    """A domain id (5..99) no other process on this machine holds: each is leased by an
    exclusive lock on /tmp/usar-arm-ros-domain-<id>.lock, kept until this process ends, so
    xdist workers and concurrent test sessions never share a graph."""
    start = next(_ids) * 7 + os.getpid()
    for k in range(95):  # 100 and 101: the benchmark's (bench/ros.py)
        domain = 5 + (start + k) % 95
        lock = open(f"/tmp/usar-arm-ros-domain-{domain}.lock", "w")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            continue
        _leases.append(lock)
        return domain
    raise RuntimeError("every ROS domain id 5..99 is leased by another process")


def ros_env(domain: int, **extra: str) -> dict[str, str]:
    """The environment of a node process on ``domain``, localhost only."""
    return {**os.environ, "ROS_DOMAIN_ID": str(domain),
            "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", **extra}


class NodeProcess:
    """`usar-arm ros ...` in a subprocess; stop() sends SIGTERM and returns its exit code."""

    def __init__(self, domain: int, args: list[str], log: Path, **env: str):
        self.log = log
        self._log_file = open(log, "w")
        self.proc = subprocess.Popen([sys.executable, "-m", "usar_arm", "ros", *args],
                                     env=ros_env(domain, **env), stdout=self._log_file,
                                     stderr=subprocess.STDOUT)

    def text(self) -> str:
        return self.log.read_text()

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 30.0) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            code = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            code = self.proc.wait(10)
        self._log_file.close()
        return code


class Client:
    """An rclpy node on ``domain`` spun in a background thread."""

    def __init__(self, domain: int, namespace: str = ""):
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node("usar_arm_test_client", namespace=namespace,
                                      context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        # rclpy's ActionClient registers a request's future only after sending it: a response
        # the spinning thread takes in between is dropped and the future never completes
        # (ros2/rclpy#1123, unfixed in these wheels). Requests and spins take turns.
        self._turn = threading.Lock()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()
        self._clients: dict[str, ActionClient] = {}
        self.feedbacks: list[Any] = []

    def _spin(self) -> None:
        while self.context.ok():
            try:
                with self._turn:
                    self.executor.spin_once(timeout_sec=0.01)
            except Exception:  # shutting down
                return

    def close(self) -> None:
        for client in self._clients.values():
            client.destroy()
        self.executor.shutdown(timeout_sec=2.0)
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)
        self._thread.join(5)

    def collect(self, msg_type: Any, topic: str, seconds: float, qos: Any = 100,
                until: Callable[[list[Any]], bool] | None = None) -> list[tuple[float, Any]]:
        """(receipt time.time(), message) of ``topic`` for ``seconds`` (or until ``until``)."""
        got: list[tuple[float, Any]] = []
        sub = self.node.create_subscription(msg_type, topic,
                                            lambda m: got.append((time.time(), m)), qos)
        end = time.monotonic() + seconds
        while time.monotonic() < end and not (until and until([m for _, m in got])):
            time.sleep(0.02)
        self.node.destroy_subscription(sub)
        return got

    def collect_many(self, topics: dict[str, Any], seconds: float
                     ) -> dict[str, list[tuple[float, Any]]]:
        """Like :meth:`collect`, several topics (name -> type) at once."""
        got: dict[str, list[tuple[float, Any]]] = {name: [] for name in topics}
        subs = [self.node.create_subscription(
            kind, name, lambda m, n=name: got[n].append((time.time(), m)), 100)
            for name, kind in topics.items()]
        time.sleep(seconds)
        for sub in subs:
            self.node.destroy_subscription(sub)
        return got

    def description(self, topic: str = "robot_description",
                    timeout: float = STARTUP_TIMEOUT_S) -> str:
        got = self.collect(String, topic, timeout, LATCHED, until=lambda ms: bool(ms))
        assert got, f"no {topic} within {timeout} s"
        return str(got[0][1].data)

    def action(self, name: str, kind: Any = FollowJointTrajectory) -> ActionClient:
        if name not in self._clients:
            self._clients[name] = ActionClient(self.node, kind, name)
        client = self._clients[name]
        assert client.wait_for_server(timeout_sec=30.0), f"no action server {name}"
        return client

    def send(self, name: str, goal: Any, timeout: float = 60.0,
             kind: Any = FollowJointTrajectory) -> Any:
        """Send a goal (of action type ``kind``); returns its handle once accepted (or
        rejected)."""
        client = self.action(name, kind)
        with self._turn:
            future = client.send_goal_async(goal, feedback_callback=self._feedback)
        return _wait(future, timeout)

    def cancel(self, handle: Any, timeout: float = 10.0) -> Any:
        """Ask to cancel the goal; its cancel response."""
        with self._turn:
            future = handle.cancel_goal_async()
        return _wait(future, timeout)

    def _feedback(self, msg: Any) -> None:
        self.feedbacks.append(msg.feedback)

    def result(self, handle: Any, timeout: float = 60.0) -> Any:
        """The goal's (status, result) once it ends."""
        with self._turn:
            future = handle.get_result_async()
        response = _wait(future, timeout)
        return response.status, response.result


def _wait(future: Any, timeout: float) -> Any:
    end = time.monotonic() + timeout
    while not future.done():
        assert time.monotonic() < end, f"no answer within {timeout} s"
        time.sleep(0.005)
    return future.result()


def make_goal(names: list[str], points: list[tuple[float, list[float]]],
              path_tolerance: dict[str, float] | None = None,
              goal_tolerance: dict[str, float] | None = None,
              stamp: tuple[int, int] = (0, 0)) -> FollowJointTrajectory.Goal:
    """A goal through (time s, positions) points."""
    trajectory = JointTrajectory(joint_names=names)
    trajectory.header.stamp.sec, trajectory.header.stamp.nanosec = stamp
    for t, q in points:
        point = JointTrajectoryPoint(positions=[float(v) for v in q])
        point.time_from_start.sec = int(t)
        point.time_from_start.nanosec = round((t - int(t)) * 1e9)
        trajectory.points.append(point)
    goal = FollowJointTrajectory.Goal(trajectory=trajectory)
    goal.path_tolerance = [JointTolerance(name=n, position=v)
                           for n, v in (path_tolerance or {}).items()]
    goal.goal_tolerance = [JointTolerance(name=n, position=v)
                           for n, v in (goal_tolerance or {}).items()]
    return goal


def latest_odometry(client: Client, topic: str = "ground_truth", seconds: float = 1.0) -> Any:
    """The latest nav_msgs/Odometry on ``topic`` within ``seconds`` (asserted to come)."""
    got = client.collect(Odometry, topic, seconds, until=lambda ms: bool(ms))
    assert got, f"no {topic}"
    return got[-1][1]


def odometry_yaw(msg: Any) -> float:
    """The yaw (rad, counter-clockwise about z up) of an Odometry message's pose."""
    q = msg.pose.pose.orientation
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def publish_twist(client: Client, v: float, w: float, seconds: float) -> None:
    """cmd_vel (``v`` m/s, ``w`` rad/s) at 10 Hz for ``seconds`` s of wall time."""
    pub = client.node.create_publisher(Twist, "cmd_vel", 10)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        msg = Twist()
        msg.linear.x, msg.angular.z = v, w
        pub.publish(msg)
        time.sleep(0.1)
    client.node.destroy_publisher(pub)


def moved_under_nan(client: Client, v: float) -> tuple[float, float]:
    """Drive at ``v`` m/s for 1 s, then keep sending NaN commands (so no timeout fires): how
    far (x, y in m) the ground truth moves over 0.5 s of them, 0.6 s after the first."""
    publish_twist(client, v, 0.0, 1.0)
    publish_twist(client, math.nan, 0.0, 0.6)
    a = latest_odometry(client).pose.pose.position
    publish_twist(client, math.nan, 0.0, 0.5)
    b = latest_odometry(client).pose.pose.position
    return b.x - a.x, b.y - a.y


def pose_change(a: Any, b: Any) -> tuple[float, float, float]:
    """From Odometry ``a`` to ``b``: the change of x, y (m) and yaw (rad, wrapped)."""
    pa, pb = a.pose.pose.position, b.pose.pose.position
    return pb.x - pa.x, pb.y - pa.y, math.remainder(odometry_yaw(b) - odometry_yaw(a), math.tau)


@contextlib.contextmanager
def node_session(folder: Path, args: list[str]) -> Iterator[tuple[Client, str, NodeProcess]]:
    """``usar-arm ros ARGS`` and a client on a domain of their own: (client, the node's URDF,
    the node); the node must stop with exit 0 on SIGTERM."""
    domain = domain_id()
    node = NodeProcess(domain, args, folder / "node.log")
    client = Client(domain)
    try:
        yield client, client.description(), node
    finally:
        client.close()
        code = node.stop()
        assert code == 0, node.text()[-3000:]
