"""A vacuum pick and place through ROS 2 alone: `usar-arm ros` serves the KR60 of a separate
`usar-arm sim`, and this script, an rclpy client, moves the arm with FollowJointTrajectory
goals, switches the vacuum with control_msgs GripperCommand goals on KR60gripper/gripper_cmd
(the result's ``stalled`` says a part is held, by the simulator's GripTruth extension), and
reads the seed's usarsim_inf status topic KR60gripper/status. Only the cell is set up outside
ROS: the part, a WorldController crate on the table; the simulator's GetSTA then says where
the part came to rest.

Needs the ros extra and its message build: pip install 'usar-arm[ros]' && usar-arm ros --setup.
Runs on its own ROS domain (ROS_DOMAIN_ID, default 43) and on localhost only.
"""

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from tempfile import mkdtemp

import numpy as np

from usar_arm import Arm
from usar_arm.arm.cycle import TOOL_DOWN
from usar_arm.core.spatial import transform
from usar_arm.ros.build import ensure_importable
from usar_arm.usarsim.world_controller import WorldControllerClient

ensure_importable()  # control_msgs and usarsim_inf come from the message build

import rclpy  # noqa: E402
from control_msgs.action import FollowJointTrajectory, GripperCommand  # noqa: E402
from rclpy.action import ActionClient  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from trajectory_msgs.msg import JointTrajectoryPoint  # noqa: E402
from usarsim_inf.msg import EffectorStatus  # noqa: E402

os.environ.setdefault("ROS_DOMAIN_ID", "43")
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
PICK, PLACE = (1.45, -0.45), (1.30, -0.60)  # on the table (x, y in base_link, m)
ABOVE, AT_PART, AT_PLACE = 1.20, 1.05, 1.06  # tool0 heights (m): the part's top is at 0.80
SUCCEEDED = 4

# 1. The cell: a simulator, a crate on its table (USARSim's WorldController), the node.
with socket.socket() as s:
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
sim = subprocess.Popen([sys.executable, "-m", "usar_arm", "sim", "--port", str(port), "-q"])
for _ in range(600):
    try:
        socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
        break
    except OSError:
        time.sleep(0.1)
wc = WorldControllerClient(port=port, timeout=10.0)
wc.connect()
wc.create("part", "WCCrate", (PICK[0], -PICK[1], -0.75), scale=(0.4, 0.4, 0.4))  # z down
node_process = subprocess.Popen([sys.executable, "-m", "usar_arm", "ros", "--host",
                                 "127.0.0.1", "--port", str(port), "-q"])

# 2. The client.
rclpy.init()
node = rclpy.create_node("vacuum_pick_client")
latest: dict[str, object] = {}
node.create_subscription(String, "robot_description", lambda m: latest.setdefault("urdf", m.data),
                         QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
node.create_subscription(JointState, "joint_states", lambda m: latest.__setitem__("joints", m), 10)
node.create_subscription(EffectorStatus, "KR60gripper/status",
                         lambda m: latest.__setitem__("vacuum", m), 10)


def spin_until(done, timeout: float) -> None:
    end = time.monotonic() + timeout
    while not done():
        if time.monotonic() > end:
            raise TimeoutError(f"nothing after {timeout} s (is `usar-arm ros` running?)")
        rclpy.spin_once(node, timeout_sec=0.05)


def run(client: ActionClient, goal, timeout: float):
    sent = client.send_goal_async(goal)
    spin_until(sent.done, 10)
    result = sent.result().get_result_async()
    spin_until(result.done, timeout)
    return result.result()


def move(name: str, height: float, xy: tuple[float, float], motion: str) -> None:
    start = np.array(latest["joints"].position)
    plan = arm.plan(pose=transform(TOOL_DOWN, (xy[0], xy[1], height)), motion=motion,
                    start=start)
    goal = FollowJointTrajectory.Goal()
    goal.trajectory.joint_names = list(arm.joint_names)
    trajectory = plan.trajectory
    for t, q, qd in zip(trajectory.t, trajectory.q, trajectory.qd, strict=True):
        point = JointTrajectoryPoint(positions=q.tolist(), velocities=qd.tolist())
        point.time_from_start.sec, point.time_from_start.nanosec = int(t), round((t % 1) * 1e9)
        goal.trajectory.points.append(point)
    response = run(trajectory_client, goal, trajectory.duration + 30)
    print(f"{name:<8} {motion.upper():<4} status {response.status} "
          f"error_code {response.result.error_code}")
    if response.status != SUCCEEDED:
        sys.exit(f"{name}: {response.result.error_string}")


def vacuum(on: bool) -> bool:
    """Switch the vacuum; whether it holds a part (the result's stalled)."""
    goal = GripperCommand.Goal()
    goal.command.position = 1.0 if on else 0.0
    response = run(gripper_client, goal, 10)
    r = response.result
    asked = time.monotonic()
    spin_until(lambda: latest.get("vacuum") is not None and time.monotonic() > asked + 0.3, 5)
    state = "CLOSE" if latest["vacuum"].state == EffectorStatus.CLOSE else "OPEN"
    print(f"vacuum {'on' if on else 'off'}: status {response.status} reached_goal "
          f"{r.reached_goal} holding {r.stalled}; KR60gripper/status says {state}")
    if response.status != SUCCEEDED or not r.reached_goal:
        sys.exit("the vacuum did not switch")
    return bool(r.stalled)


try:
    spin_until(lambda: {"urdf", "joints"} <= set(latest), 180)
    folder = Path(mkdtemp(prefix="ros-vacuum-pick-"))
    (folder / "KR60.urdf").write_text(str(latest["urdf"]))
    arm = Arm.from_files(folder / "KR60.urdf")  # offline: plan only
    trajectory_client = ActionClient(node, FollowJointTrajectory,
                                     "KR60Arm_controller/follow_joint_trajectory")
    gripper_client = ActionClient(node, GripperCommand, "KR60gripper/gripper_cmd")
    for c in (trajectory_client, gripper_client):
        assert c.wait_for_server(timeout_sec=60), "no action server"

    move("approach", ABOVE, PICK, "ptp")
    move("down", AT_PART, PICK, "lin")
    if not vacuum(True):
        sys.exit("the vacuum holds nothing: the part is not under the suction cup")
    move("lift", ABOVE, PICK, "lin")
    move("carry", ABOVE, PLACE, "lin")
    move("lower", AT_PLACE, PLACE, "lin")
    if vacuum(False):
        sys.exit("the vacuum still holds the part")
    move("retreat", ABOVE, PLACE, "lin")
    time.sleep(1.0)  # the part falls its centimetre and rests
    rest = wc.get_sta(name="part").objects[0].location  # the simulator's truth, z down
    miss = float(np.hypot(rest[0] - PLACE[0], -rest[1] - PLACE[1]))
    print(f"part placed at x {rest[0]:.3f} y {-rest[1]:.3f} z {-rest[2]:.3f} m (base_link), "
          f"{miss * 1000:.1f} mm from the place point")
    if miss > 0.01:
        sys.exit("the part is not where it was placed")
    print("vacuum pick and place done through ROS 2")
finally:
    node.destroy_node()
    rclpy.shutdown()
    node_process.send_signal(signal.SIGINT)
    node_process.wait(60)
    wc.close()
    sim.terminate()
    sim.wait(30)
