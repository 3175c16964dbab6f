"""The ROS 2 stage's instrument: `usar-arm ros` (embedded KR60) measured from another process
by its own rclpy client, on a private ROS domain on localhost. ``bench/run.py --stages ros``
runs it (``bench/ros.py``); alone:

    python bench/ros_probe.py [--seconds 60] [--goal-seconds 600] [--json FILE]

Measures:

* /joint_states: messages per second and gaps (a gap above 1.8 ASTA periods is a dropped
  line); latency from the ASTA line's arrival in the node (the message's stamp) to this
  subscriber's callback (p50, p99, max), both read on the machine's system clock, and the
  same path in three hops by the middleware's own timestamps (source: the node's publish call;
  received: this process's DDS receipt): the node's share, the middleware's, this
  subscriber's rclpy dispatch;
* /tf: tool0 composed from tf_static and each tf message against Pinocchio's FK of the joint
  state with the same stamp (this instrument's own FK: it shares no code with the node's tf);
* FollowJointTrajectory: time from sending a goal to its acceptance, and to the error code
  of a refused goal (unknown joint), over many goals;
* the node's CPU (its /proc times) at idle and while executing goals every 2 s, and its
  resident memory and thread count every 30 s of that (``--goal-seconds 600``: the
  10-minute run).

Needs the ros extra and its message build (usar-arm ros --setup).
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import ros_figures
from ros_figures import stats as _stats

from usar_arm.planning.kinematics import KinematicModel
from usar_arm.ros.build import ensure_importable

ensure_importable()

import rclpy  # noqa: E402
from control_msgs.action import FollowJointTrajectory  # noqa: E402
from rclpy.action import ActionClient  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402
from trajectory_msgs.msg import JointTrajectoryPoint  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
ACTION = "KR60Arm_controller/follow_joint_trajectory"


class Probe:
    """The client: records every message it receives with its receipt time."""

    def __init__(self) -> None:
        self.node = rclpy.create_node("usar_arm_bench")
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.urdf = ""
        self.static: list[Any] = []
        self.states: list[tuple[float, Any]] = []
        self.hops: list[tuple[float, float]] = []
        self.tf: list[Any] = []
        self.node.create_subscription(String, "robot_description",
                                      lambda m: setattr(self, "urdf", m.data), latched)
        self.node.create_subscription(TFMessage, "tf_static", self.static.append, latched)
        self.node.create_subscription(JointState, "joint_states", self._state, 1000)
        self.node.create_subscription(TFMessage, "tf", self.tf.append, 1000)
        self.action = ActionClient(self.node, FollowJointTrajectory, ACTION)

    def _state(self, msg: JointState, info: Any) -> None:
        """A joint state, with when this callback ran and the middleware's own times (ns since
        the epoch): the node's publish call (source) and this process's receipt."""
        self.states.append((time.time(), msg))
        self.hops.append((info["source_timestamp"] * 1e-9, info["received_timestamp"] * 1e-9))

    def spin(self, seconds: float, until: Any = None) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end and not (until and until()):
            rclpy.spin_once(self.node, timeout_sec=0.01)

    def wait(self, future: Any, timeout: float) -> Any:
        self.spin(timeout, future.done)
        if not future.done():
            raise TimeoutError(f"no answer within {timeout} s")
        return future.result()


def _goal(names: list[str], q: np.ndarray, seconds: float) -> FollowJointTrajectory.Goal:
    goal = FollowJointTrajectory.Goal()
    goal.trajectory.joint_names = names
    point = JointTrajectoryPoint(positions=q.tolist())
    point.time_from_start.sec = int(seconds)
    point.time_from_start.nanosec = int((seconds % 1) * 1e9)
    goal.trajectory.points.append(point)
    return goal


def _goals(probe: Probe, names: list[str], seconds: float, refused: bool,
           home: np.ndarray) -> dict[str, Any]:
    """Goals every 2 s (small moves back and forth between ``home``, the arm's joints when the
    run began, and a configuration near it), or refused ones; latencies in ms."""
    accept, refuse, codes, errors = [], [], [], []
    end = time.monotonic() + seconds
    away = home + np.array([0.2, -0.1, 0.1, 0.2, 0.2, 0.2])
    k = 0
    while time.monotonic() < end:
        q = np.array(probe.states[-1][1].position)
        if refused:
            goal = _goal([*names[:5], "joint_x"], q, 1.0)
        else:  # back and forth between two fixed configurations
            goal = _goal(names, away if k % 2 == 0 else home, 1.5)
            k += 1
        begin = time.perf_counter()
        handle = probe.wait(probe.action.send_goal_async(goal), 10)
        accept.append((time.perf_counter() - begin) * 1000)
        result = probe.wait(handle.get_result_async(), 30)
        if refused:
            refuse.append((time.perf_counter() - begin) * 1000)
        codes.append(result.result.error_code)
        if result.result.error_code != 0 and not refused and len(errors) < 5:
            errors.append(result.result.error_string)
        probe.spin(max(0.0, 2.0 - (time.perf_counter() - begin)) if not refused else 0.05)
    out = {"goals": len(accept), "accept_ms": _stats(accept), "latencies": accept,
           "error_codes": {str(c): codes.count(c) for c in sorted(set(codes))}, "errors": errors}
    if refused:
        out["refused_result_ms"] = _stats(refuse)
    return out


def _tf_error(probe: Probe, model: KinematicModel) -> dict[str, Any]:
    def tree(msg: Any) -> ros_figures.Tree:
        return {t.child_frame_id: (t.header.frame_id, _matrix(t)) for t in msg.transforms}

    static = {k: v for m in probe.static for k, v in tree(m).items()}
    positions = {(m.header.stamp.sec, m.header.stamp.nanosec): m.position
                 for _, m in probe.states}
    messages = [((m.transforms[0].header.stamp.sec, m.transforms[0].header.stamp.nanosec),
                 tree(m)) for m in probe.tf if m.transforms]
    return ros_figures.tool0_error(static, messages, positions, model)


def _matrix(t: Any) -> np.ndarray:
    return ros_figures.matrix(t.transform.translation, t.transform.rotation)


def _joint_states(records: list[tuple[float, Any]], hops: list[tuple[float, float]]
                  ) -> dict[str, Any]:
    stamps = np.array([m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for _, m in records])
    received = np.array([t for t, _ in records])
    source, middleware = np.array(hops).reshape(-1, 2).T
    out = ros_figures.joint_state_figures(stamps, received)
    # the same path in three hops (each its own percentiles: tails do not add up): node: line
    # arrival -> publish call; middleware: publish call -> receipt in this process; subscriber:
    # receipt -> this rclpy callback
    out["hops_ms"] = {"node": _stats(((source - stamps) * 1000).tolist()),
                      "middleware": _stats(((middleware - source) * 1000).tolist()),
                      "subscriber": _stats(((received - middleware) * 1000).tolist())}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=60.0, help="joint_states window (s)")
    ap.add_argument("--json", type=Path, default=None, help="write the results here")
    ap.add_argument("--goal-seconds", type=float, default=30.0,
                    help="how long goals are sent every 2 s (600: the 10-minute run)")
    ap.add_argument("--domain", type=int, default=100, help="ROS_DOMAIN_ID (default 100)")
    ap.add_argument("--sim-port", type=int, default=0,
                    help="run the simulator as its own process (usar-arm sim on this port) and "
                         "the node as its client, as with a USARSim server; default: the "
                         "node's embedded simulator, in the node's process")
    a = ap.parse_args(argv)
    os.environ["ROS_DOMAIN_ID"] = str(a.domain)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    sim = None
    where: list[str] = []
    if a.sim_port:
        sim = subprocess.Popen([sys.executable, "-m", "usar_arm", "sim", "-q", "--port",
                                str(a.sim_port)], cwd=ROOT)
        time.sleep(3.0)  # the server listens within a second; the node retries its connect
        where = ["--host", "127.0.0.1", "--port", str(a.sim_port)]
    node = subprocess.Popen([sys.executable, "-m", "usar_arm", "ros", "-q", *where], cwd=ROOT)
    rclpy.init()
    probe = Probe()
    try:
        probe.spin(180, lambda: bool(probe.urdf and probe.static and probe.states))
        model = KinematicModel(probe.urdf)
        names = list(probe.states[-1][1].name)
        home = np.array(probe.states[-1][1].position)  # the goals move about this, all run
        start = ros_figures.proc(node.pid)
        probe.states.clear()
        probe.hops.clear()
        probe.tf.clear()
        before = ros_figures.proc(node.pid)["cpu_s"]
        probe.spin(a.seconds)
        idle_cpu = (ros_figures.proc(node.pid)["cpu_s"] - before) / a.seconds
        streams = _joint_states(probe.states, probe.hops)
        tf = _tf_error(probe, model)
        moving, busy_cpu = ros_figures.goal_period(
            lambda s: _goals(probe, names, s, False, home), node.pid, a.goal_seconds)
        refused = _goals(probe, names, 5.0, True, home)
        refused.pop("latencies")
        refused.pop("errors")
        end = ros_figures.proc(node.pid)
        doc = {"stage": "ros", "joint_states": streams, "tf": tf, "goals": moving,
               "refused_goals": refused,
               "node": ros_figures.node_figures(idle_cpu, busy_cpu, start, end),
               "targets": {"joint_states_latency_p99_ms<=2": streams["latency_ms"]["p99"] <= 2,
                           "joint_states_none_dropped": streams["dropped"] == 0,
                           "tf_equals_fk_1e-9": tf["tool0_max_error_m"] <= 1e-9
                           and tf["tool0_max_rotation_error"] <= 1e-9,
                           "goal_accept_p99_ms<=20": moving["accept_ms"].get("p99", 0) <= 20
                           and refused["accept_ms"].get("p99", 0) <= 20
                           if moving["goals"] else None},
               "load_average_1min_at_end": os.getloadavg()[0], "cpus": os.cpu_count(),
               "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    finally:
        probe.node.destroy_node()
        rclpy.shutdown()
        node.send_signal(signal.SIGINT)
        code = node.wait(60)
        if sim is not None:
            sim.send_signal(signal.SIGINT)
            sim.wait(30)
    doc["node"]["exit_code"] = code
    doc["simulator"] = (f"usar-arm sim in its own process (port {a.sim_port})" if a.sim_port
                        else "embedded, in the node's process")
    ros_figures.emit(doc, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
