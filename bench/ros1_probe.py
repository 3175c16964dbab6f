"""The ROS 1 stage's instrument: `usar-arm ros --ros1` (embedded KR60) measured from another
process by its own rospy client, against a roscore of its own on localhost. Runs in the ROS 1
interpreter (bench/ros.py starts it there); alone:

    <ROS 1 python> bench/ros1_probe.py [--seconds 60] [--goal-seconds 600] [--json FILE]

Measures what bench/ros_probe.py measures on ROS 2 (the figures by bench/ros_figures.py):

* /joint_states: rate, drops, latency from the ASTA line's arrival in the node (the message's
  stamp, the system clock) to this subscriber's callback (TCP_NODELAY, as ROS 1 clients ask);
* /tf: tool0 composed from /tf_static and each /tf message against Pinocchio's FK of the
  joint state with the same stamp (this instrument's own FK);
* FollowJointTrajectory through actionlib: from send_goal to the goal's ACTIVE status seen by a
  SimpleActionClient, and to a refused goal's REJECTED (unknown joint);
* the node's CPU, memory and threads every 30 s of goals (600 s: the 10-minute run).
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import actionlib
import numpy as np
import ros_figures
import rospy
from actionlib_msgs.msg import GoalStatus
from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryGoal
from ros_figures import stats
from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage
from trajectory_msgs.msg import JointTrajectoryPoint

from usar_arm.planning.kinematics import KinematicModel

ROOT = Path(__file__).resolve().parents[1]
ACTION = "KR60Arm_controller/follow_joint_trajectory"


class Probe:
    """The client: every message with its receipt time."""

    def __init__(self) -> None:
        self.static: list[Any] = []
        self.states: list[tuple[float, Any]] = []
        self.tf: list[Any] = []
        rospy.Subscriber("tf_static", TFMessage, self.static.append, queue_size=10)
        rospy.Subscriber("joint_states", JointState,
                         lambda m: self.states.append((time.time(), m)), queue_size=1000,
                         tcp_nodelay=True)
        rospy.Subscriber("tf", TFMessage, self.tf.append, queue_size=1000, tcp_nodelay=True)
        self.action = actionlib.SimpleActionClient(ACTION, FollowJointTrajectoryAction)


def _goal(names: list[str], q: np.ndarray, seconds: float) -> FollowJointTrajectoryGoal:
    goal = FollowJointTrajectoryGoal()
    goal.trajectory.joint_names = names
    goal.trajectory.points.append(JointTrajectoryPoint(
        positions=q.tolist(), time_from_start=rospy.Duration.from_sec(seconds)))
    return goal


def _goals(probe: Probe, names: list[str], seconds: float, refused: bool,
           home: np.ndarray) -> dict[str, Any]:
    """Goals every 2 s back and forth about ``home`` (or refused ones); latencies in ms."""
    accept, codes, errors = [], [], []
    end = time.monotonic() + seconds
    away = home + np.array([0.2, -0.1, 0.1, 0.2, 0.2, 0.2])
    k = 0
    while time.monotonic() < end:
        if refused:
            goal = _goal([*names[:5], "joint_x"], home, 1.0)
        else:
            goal = _goal(names, away if k % 2 == 0 else home, 1.5)
            k += 1
        begin = time.perf_counter()
        probe.action.send_goal(goal)
        while probe.action.get_state() == GoalStatus.PENDING and \
                time.perf_counter() - begin < 10:
            time.sleep(0.0002)
        accept.append((time.perf_counter() - begin) * 1000)
        probe.action.wait_for_result(rospy.Duration(30))
        result = probe.action.get_result()
        code = result.error_code if result is not None else None
        codes.append(code)
        if code != 0 and not refused and len(errors) < 5:
            errors.append(None if result is None else result.error_string)
        time.sleep(max(0.0, 2.0 - (time.perf_counter() - begin)) if not refused else 0.05)
    out = {"goals": len(accept), "accept_ms": stats(accept), "latencies": accept,
           "error_codes": {str(c): codes.count(c) for c in sorted(set(codes), key=str)},
           "errors": errors}
    if refused:
        out["refused_result_ms"] = out["accept_ms"]  # REJECTED is the first state it leaves to
    return out


def _tree(msg: Any) -> ros_figures.Tree:
    return {t.child_frame_id: (t.header.frame_id,
                               ros_figures.matrix(t.transform.translation, t.transform.rotation))
            for t in msg.transforms}


def _tf_error(probe: Probe, model: KinematicModel) -> dict[str, Any]:
    static = {k: v for m in probe.static for k, v in _tree(m).items()}
    positions = {(m.header.stamp.secs, m.header.stamp.nsecs): m.position
                 for _, m in probe.states}
    messages = [((m.transforms[0].header.stamp.secs, m.transforms[0].header.stamp.nsecs),
                 _tree(m)) for m in probe.tf if m.transforms]
    return ros_figures.tool0_error(static, messages, positions, model)


def _master(folder: Path) -> tuple[subprocess.Popen[bytes], str]:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = int(s.getsockname()[1])
    proc = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.STDOUT,
                            env={**os.environ, "ROS_HOME": str(folder)})
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
            return proc, f"http://127.0.0.1:{port}"
        except OSError:
            time.sleep(0.1)
    raise RuntimeError("roscore did not start")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=60.0, help="joint_states window (s)")
    ap.add_argument("--json", type=Path, default=None, help="write the results here")
    ap.add_argument("--goal-seconds", type=float, default=30.0,
                    help="how long goals are sent every 2 s (600: the 10-minute run)")
    a = ap.parse_args(argv)
    folder = Path(os.environ.get("TMPDIR", "/tmp")) / f"usar-arm-ros1-probe-{os.getpid()}"
    folder.mkdir(parents=True, exist_ok=True)
    master, uri = _master(folder)
    os.environ.update(ROS_MASTER_URI=uri, ROS_HOSTNAME="127.0.0.1", ROS_HOME=str(folder))
    node = subprocess.Popen([sys.executable, "-m", "usar_arm", "ros", "--ros1", "-q"], cwd=ROOT)
    rospy.init_node("usar_arm_bench", disable_signals=True)
    probe = Probe()
    try:
        end = time.monotonic() + 240
        while not (rospy.has_param("robot_description") and probe.static and probe.states):
            if time.monotonic() > end:
                raise TimeoutError("the node served nothing within 240 s")
            time.sleep(0.1)
        probe.action.wait_for_server(rospy.Duration(30))
        model = KinematicModel(rospy.get_param("robot_description"))
        names = list(probe.states[-1][1].name)
        home = np.array(probe.states[-1][1].position)
        start = ros_figures.proc(node.pid)
        probe.states.clear()
        probe.tf.clear()
        before = start["cpu_s"]
        time.sleep(a.seconds)
        idle_cpu = (ros_figures.proc(node.pid)["cpu_s"] - before) / a.seconds
        records = list(probe.states)
        streams = ros_figures.joint_state_figures(
            np.array([m.header.stamp.to_sec() for _, m in records]),
            np.array([t for t, _ in records]))
        seqs = np.array([m.header.seq for _, m in records])
        streams["seq_gaps"] = int(np.sum(np.diff(seqs) != 1))
        tf = _tf_error(probe, model)
        moving, busy_cpu = ros_figures.goal_period(
            lambda s: _goals(probe, names, s, False, home), node.pid, a.goal_seconds)
        refused = _goals(probe, names, 5.0, True, home)
        refused.pop("latencies")
        refused.pop("errors")
        end_proc = ros_figures.proc(node.pid)
        doc = {"stage": "ros", "middleware": "ROS 1 (Debian's rospy, actionlib)",
               "joint_states": streams, "tf": tf, "goals": moving, "refused_goals": refused,
               "node": ros_figures.node_figures(idle_cpu, busy_cpu, start, end_proc),
               "load_average_1min_at_end": os.getloadavg()[0], "cpus": os.cpu_count(),
               "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    finally:
        rospy.signal_shutdown("done")
        node.send_signal(signal.SIGINT)
        code = node.wait(60)
        master.send_signal(signal.SIGINT)
        master.wait(30)
    doc["node"]["exit_code"] = code
    doc["simulator"] = "embedded, in the node's process"
    ros_figures.emit(doc, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
