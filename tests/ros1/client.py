"""A ROS 1 client of `usar-arm ros --ros1`, as a user writes one (rospy, actionlib), run in the
ROS 1 interpreter by the tests (tests/ros1/helpers.py). It shares no code with the node: it
reads what ROS 1 delivers and prints one JSON line.

    client.py description [--timeout S]
    client.py record --seconds S --out FILE TOPIC:PKG/Type ...
    client.py goal --action NAME --spec JSON
    client.py cycle --action NAME
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Any

import actionlib
import genpy
import numpy as np
import rospy
from actionlib_msgs.msg import GoalStatus
from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryGoal, JointTolerance
from tf2_msgs.msg import TFMessage
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[2]))
from tests.ros1.transforms import matrix

STATUS = {v: k for k, v in vars(GoalStatus).items() if k.isupper() and isinstance(v, int)}


def plain(msg: Any) -> Any:
    """A genpy message as JSON-able data (times as [secs, nsecs])."""
    if isinstance(msg, (genpy.Time, genpy.Duration)):
        return [msg.secs, msg.nsecs]
    if isinstance(msg, genpy.Message):
        return {slot: plain(getattr(msg, slot)) for slot in msg.__slots__}
    if isinstance(msg, (list, tuple)):
        return [plain(v) for v in msg]
    if isinstance(msg, bytes):
        return list(msg)
    if isinstance(msg, float) and not math.isfinite(msg):
        return repr(msg)
    return msg


def message_class(name: str) -> Any:
    package, kind = name.split("/")
    module = __import__(f"{package}.msg", fromlist=[kind])
    return getattr(module, kind)


def description(args: argparse.Namespace) -> dict[str, Any]:
    rospy.init_node("usar_arm_test_client", anonymous=True, disable_signals=True)
    end = time.monotonic() + args.timeout
    while not rospy.has_param("robot_description"):
        if time.monotonic() > end:
            raise SystemExit(f"no robot_description parameter within {args.timeout} s")
        time.sleep(0.2)
    return {"urdf": rospy.get_param("robot_description"),
            "srdf": rospy.get_param("robot_description_semantic", "")}


def record(args: argparse.Namespace) -> dict[str, Any]:
    """Every message of the topics for the window, with its receipt time."""
    rospy.init_node("usar_arm_test_recorder", anonymous=True, disable_signals=True)
    got: dict[str, list[Any]] = {}
    subs = []
    for item in args.topics:
        topic, kind = item.split(":")
        got[topic] = []
        subs.append(rospy.Subscriber(topic, message_class(kind),
                                     lambda m, t=topic: got[t].append((time.time(), plain(m))),
                                     queue_size=1000, tcp_nodelay=True))
    time.sleep(args.seconds)
    for sub in subs:
        sub.unregister()
    with open(args.out, "w") as f:
        json.dump(got, f)
    return {topic: len(v) for topic, v in got.items()}


def _goal(names: list[str], points: list[list[Any]], tolerances: dict[str, Any]
          ) -> FollowJointTrajectoryGoal:
    goal = FollowJointTrajectoryGoal(trajectory=JointTrajectory(joint_names=names))
    for t, q in points:
        goal.trajectory.points.append(JointTrajectoryPoint(
            positions=[float(v) for v in q], time_from_start=rospy.Duration.from_sec(t)))
    goal.goal_tolerance = [JointTolerance(name=n, position=v)
                           for n, v in tolerances.get("goal", {}).items()]
    goal.path_tolerance = [JointTolerance(name=n, position=v)
                           for n, v in tolerances.get("path", {}).items()]
    return goal


def _send(client: actionlib.SimpleActionClient, goal: FollowJointTrajectoryGoal,
          timeout: float = 120.0) -> dict[str, Any]:
    sent = time.perf_counter()
    client.send_goal(goal)
    accepted = None
    while accepted is None and time.perf_counter() - sent < 10:
        state = client.get_state()
        if state != GoalStatus.PENDING:
            accepted = time.perf_counter() - sent
        time.sleep(0.0005)
    client.wait_for_result(rospy.Duration(timeout))
    result = client.get_result()
    return {"status": STATUS.get(client.get_state(), str(client.get_state())),
            "error_code": None if result is None else result.error_code,
            "error_string": None if result is None else result.error_string,
            "state_changed_s": accepted}


def goal(args: argparse.Namespace) -> dict[str, Any]:
    rospy.init_node("usar_arm_test_goal", anonymous=True, disable_signals=True)
    spec = json.loads(args.spec)
    client = actionlib.SimpleActionClient(args.action, FollowJointTrajectoryAction)
    if not client.wait_for_server(rospy.Duration(30)):
        raise SystemExit(f"no action server {args.action}")
    return _send(client, _goal(spec["names"], spec["points"], spec.get("tolerances", {})))


def preempt(args: argparse.Namespace) -> dict[str, Any]:
    """Goal ``first`` sent; once ACTIVE for ``--after`` s, goal ``second`` from a second
    client: both outcomes."""
    rospy.init_node("usar_arm_test_preempt", anonymous=True, disable_signals=True)
    spec = json.loads(args.spec)
    clients = [actionlib.SimpleActionClient(args.action, FollowJointTrajectoryAction)
               for _ in range(2)]
    for c in clients:
        if not c.wait_for_server(rospy.Duration(30)):
            raise SystemExit(f"no action server {args.action}")
    first = _goal(spec["names"], spec["first"], {})
    clients[0].send_goal(first)
    end = time.monotonic() + 10
    while clients[0].get_state() != GoalStatus.ACTIVE and time.monotonic() < end:
        time.sleep(0.005)
    time.sleep(args.after)
    second = _send(clients[1], _goal(spec["names"], spec["second"], {}))
    clients[0].wait_for_result(rospy.Duration(30))
    result = clients[0].get_result()
    return {"first": {"status": STATUS.get(clients[0].get_state()),
                      "error_code": None if result is None else result.error_code,
                      "error_string": None if result is None else result.error_string},
            "second": second}


def _matrix(t: Any) -> np.ndarray:
    return matrix(plain(t))


def _trajectory_goal(names: list[str], trajectory: Any) -> FollowJointTrajectoryGoal:
    """A usar-arm trajectory (every sample, with its velocities) as a goal."""
    goal = FollowJointTrajectoryGoal(trajectory=JointTrajectory(joint_names=names))
    for t, q, qd in zip(trajectory.t, trajectory.q, trajectory.qd, strict=True):
        goal.trajectory.points.append(JointTrajectoryPoint(
            positions=q.tolist(), velocities=qd.tolist(),
            time_from_start=rospy.Duration.from_sec(float(t))))
    return goal


def cycle(args: argparse.Namespace) -> dict[str, Any]:
    """The demo's pick-and-place cycle (as examples/08_ros_pick_and_place.py sends it over
    ROS 2), planned offline with usar-arm from the node's own description, sent move by move;
    tool0's error by the simulator's truth (the tip GroundTruth frame on tf) after each."""
    import tempfile
    from pathlib import Path

    from sensor_msgs.msg import JointState

    from usar_arm import Arm
    from usar_arm.arm.cycle import pick_and_place, tcp_offset

    rospy.init_node("usar_arm_test_cycle", anonymous=True, disable_signals=True)
    folder = Path(tempfile.mkdtemp(prefix="ros1-cycle-"))
    (folder / "KR60.urdf").write_text(rospy.get_param("robot_description"))
    (folder / "KR60.srdf").write_text(rospy.get_param("robot_description_semantic"))
    arm = Arm.from_files(folder / "KR60.urdf", folder / "KR60.srdf")
    latest: dict[str, Any] = {}

    def on_tf(msg: TFMessage) -> None:
        for t in msg.transforms:
            if t.child_frame_id == f"{args.truth}_truth":
                latest["truth"] = (time.monotonic(), t.transform)

    rospy.Subscriber("tf", TFMessage, on_tf, queue_size=100)
    rospy.Subscriber("joint_states", JointState, lambda m: latest.__setitem__("joints", m),
                     queue_size=10)
    client = actionlib.SimpleActionClient(args.action, FollowJointTrajectoryAction)
    if not client.wait_for_server(rospy.Duration(30)):
        raise SystemExit(f"no action server {args.action}")
    end = time.monotonic() + 30
    while not {"joints", "truth"} <= set(latest) and time.monotonic() < end:
        time.sleep(0.05)
    zero = np.zeros(len(arm.joint_names))
    tool0_in_truth = np.linalg.inv(arm.fk(zero, args.truth)) @ arm.fk(zero)
    out = []
    home = arm.plan(joints=arm.home, scene=args.scene,  # from wherever other clients left it
                    start=np.array(latest["joints"].position)).trajectory
    _send(client, _trajectory_goal(list(arm.joint_names), home), home.duration + 30)
    time.sleep(0.5)
    for move in pick_and_place(arm.home, tcp_offset(arm.robot)):
        start = np.array(latest["joints"].position)
        plan = arm.plan(joints=move.joints, pose=move.pose, motion=move.motion,
                        scene=args.scene, start=start)
        trajectory = plan.trajectory
        sent = _send(client, _trajectory_goal(list(arm.joint_names), trajectory),
                     trajectory.duration + 30)
        ended = time.monotonic()
        while latest["truth"][0] < ended + 0.2 and time.monotonic() < ended + 5:
            time.sleep(0.02)
        true_tool0 = _matrix(latest["truth"][1]) @ tool0_in_truth
        target = move.pose if move.pose is not None else arm.fk(move.joints)
        cos = (np.trace(target[:3, :3].T @ true_tool0[:3, :3]) - 1) / 2
        out.append({"name": move.name, "motion": move.motion, **sent,
                    "duration_s": float(trajectory.duration),
                    "tool0_error_m": float(np.linalg.norm(true_tool0[:3, 3] - target[:3, 3])),
                    "tool0_error_rad": float(np.arccos(np.clip(cos, -1.0, 1.0)))})
    return {"moves": out}


def main() -> int:
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("description")
    p.add_argument("--timeout", type=float, default=120.0)
    p = sub.add_parser("record")
    p.add_argument("--seconds", type=float, required=True)
    p.add_argument("--out", required=True)
    p.add_argument("topics", nargs="+")
    p = sub.add_parser("goal")
    p.add_argument("--action", required=True)
    p.add_argument("--spec", required=True)
    p = sub.add_parser("preempt")
    p.add_argument("--action", required=True)
    p.add_argument("--spec", required=True)
    p.add_argument("--after", type=float, default=1.5)
    p = sub.add_parser("cycle")
    p.add_argument("--action", required=True)
    p.add_argument("--truth", default="KR60ArmTipTruth")
    p.add_argument("--scene", default="table")
    args = parser.parse_args()
    result = {"description": description, "record": record, "goal": goal,
              "preempt": preempt, "cycle": cycle}[args.command](args)
    print(json.dumps(result))
    sys.stdout.flush()
    rospy.signal_shutdown("done")
    return 0


if __name__ == "__main__":
    sys.exit(main())
