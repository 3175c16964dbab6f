"""The pick-and-place cycle through ROS 2: `usar-arm ros` serves the arm in one process, and
this script is the ROS client a user would write, in another. It reads the description from
/robot_description (and the SRDF from /robot_description_semantic), waits for tf, plans each
move of the demo's cycle offline with usar-arm, sends it as a FollowJointTrajectory goal, and
prints per move the action's result and tool0's error by the simulator's truth (its tip
GroundTruth sensor's frame on tf, printed at full precision).

Needs the ros extra and its message build: pip install 'usar-arm[ros]' && usar-arm ros --setup.
Runs on its own ROS domain (ROS_DOMAIN_ID, default 42) and on localhost only.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from tempfile import mkdtemp

import numpy as np

from usar_arm import Arm
from usar_arm.arm.cycle import pick_and_place, tcp_offset
from usar_arm.ros.build import ensure_importable

ensure_importable()  # tf2_msgs and control_msgs come from the message build

import rclpy  # noqa: E402
from control_msgs.action import FollowJointTrajectory  # noqa: E402
from rclpy.action import ActionClient  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402
from trajectory_msgs.msg import JointTrajectoryPoint  # noqa: E402

os.environ.setdefault("ROS_DOMAIN_ID", "42")
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
ACTION = "KR60Arm_controller/follow_joint_trajectory"
TRUTH = "KR60ArmTipTruth"
STATUS = {4: "SUCCEEDED", 5: "CANCELED", 6: "ABORTED"}

# 1. The node, in its own process (the embedded simulator prints full-precision numbers).
node_process = subprocess.Popen([sys.executable, "-m", "usar_arm", "ros", "--scene", "table",
                                 "--wire-precision", "full", "-q"])

# 2. The client: latest messages of each topic, kept by subscriptions.
rclpy.init()
node = rclpy.create_node("pick_and_place_client")
latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
latest: dict[str, object] = {}
node.create_subscription(String, "robot_description",
                         lambda m: latest.setdefault("urdf", m.data), latched)
node.create_subscription(String, "robot_description_semantic",
                         lambda m: latest.setdefault("srdf", m.data), latched)
node.create_subscription(JointState, "joint_states",
                         lambda m: latest.__setitem__("joints", m), 10)


def on_tf(msg: TFMessage) -> None:
    for t in msg.transforms:
        if t.child_frame_id == f"{TRUTH}_truth":
            latest["truth"] = (time.monotonic(), t.transform)


node.create_subscription(TFMessage, "tf", on_tf, 100)


def spin_until(done, timeout: float) -> None:
    end = time.monotonic() + timeout
    while not done():
        if time.monotonic() > end:
            raise TimeoutError(f"nothing after {timeout} s (is `usar-arm ros` running?)")
        rclpy.spin_once(node, timeout_sec=0.05)


def matrix(transform) -> np.ndarray:
    """4x4 of a geometry_msgs/Transform."""
    x, y, z, w = (transform.rotation.x, transform.rotation.y, transform.rotation.z,
                  transform.rotation.w)
    out = np.eye(4)
    out[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                   [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                   [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    out[:3, 3] = (transform.translation.x, transform.translation.y, transform.translation.z)
    return out


try:
    spin_until(lambda: {"urdf", "srdf", "joints", "truth"} <= set(latest), 180)
    folder = Path(mkdtemp(prefix="ros-pick-and-place-"))
    (folder / "KR60.urdf").write_text(str(latest["urdf"]))
    (folder / "KR60.srdf").write_text(str(latest["srdf"]))
    arm = Arm.from_files(folder / "KR60.urdf", folder / "KR60.srdf")  # offline: plan only
    zero = np.zeros(len(arm.joint_names))
    tool0_in_truth = np.linalg.inv(arm.fk(zero, TRUTH)) @ arm.fk(zero)  # a rigid offset
    client = ActionClient(node, FollowJointTrajectory, ACTION)
    assert client.wait_for_server(timeout_sec=60), f"no action server {ACTION}"

    print(f"{'move':<9} {'type':<4} {'result':<9} {'code':>4} {'motion s':>8} "
          f"{'tool0 mm':>8} {'tool0 mrad':>10}")
    worst = 0.0
    failed: list[str] = []
    for move in pick_and_place(arm.home, tcp_offset(arm.robot)):
        start = np.array(latest["joints"].position)
        plan = arm.plan(joints=move.joints, pose=move.pose, motion=move.motion, scene="table",
                        start=start)
        trajectory = plan.trajectory
        goal = FollowJointTrajectory.Goal()
        goal.trajectory.joint_names = list(arm.joint_names)
        for t, q, qd in zip(trajectory.t, trajectory.q, trajectory.qd, strict=True):
            point = JointTrajectoryPoint(positions=q.tolist(), velocities=qd.tolist())
            point.time_from_start.sec, point.time_from_start.nanosec = \
                int(t), round((t - int(t)) * 1e9)
            goal.trajectory.points.append(point)
        sent = client.send_goal_async(goal)
        spin_until(sent.done, 10)
        result_future = sent.result().get_result_async()
        spin_until(result_future.done, trajectory.duration + 30)
        response = result_future.result()
        ended = time.monotonic()
        # the truth frame from a reading taken after the move ended
        spin_until(lambda ended=ended: latest["truth"][0] > ended + 0.2, 5)
        true_tool0 = matrix(latest["truth"][1]) @ tool0_in_truth
        target = move.pose if move.pose is not None else arm.fk(move.joints)
        error_m = float(np.linalg.norm(true_tool0[:3, 3] - target[:3, 3]))
        cos = (np.trace(target[:3, :3].T @ true_tool0[:3, :3]) - 1) / 2
        error_rad = float(np.arccos(np.clip(cos, -1.0, 1.0)))
        print(f"{move.name:<9} {move.motion.upper():<4} "
              f"{STATUS.get(response.status, response.status):<9} "
              f"{response.result.error_code:>4} {trajectory.duration:>8.2f} "
              f"{error_m * 1000:>8.2f} {error_rad * 1000:>10.2f}")
        worst = max(worst, error_m)
        if response.status != 4 or response.result.error_code != 0:
            failed.append(move.name)
    print(f"cycle done through ROS 2; worst tool0 error {worst * 1000:.2f} mm (the demo's "
          "target: 1 mm)")
    if failed or worst > 1e-3:
        sys.exit(f"not every move succeeded within 1 mm: failed {failed or 'none'}, worst "
                 f"{worst * 1000:.2f} mm")
finally:
    node.destroy_node()
    rclpy.shutdown()
    node_process.send_signal(signal.SIGINT)
    node_process.wait(60)
