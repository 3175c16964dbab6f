"""Any arm's URDF: the UR5 of example-robot-data, with its meshes.

usar-arm plans for any serial arm's URDF, not only the arms it learns: the collision meshes are
read with trimesh, ``package://`` paths resolve as ROS tools resolve them (here through the
folder named after the package), and the IK takes the closed form the arm's axes allow: the
UR5's three parallel axes have one (an arm with neither that nor an ortho-parallel structure
gets the numeric solver with restarts). The SRDF gives the disabled collision pairs (links
joined by a joint are never checked against each other, listed or not, as in MoveIt's setup
assistant). The scene is the UR5's own: the shipped scenes are the KR60's cell.
"""

from pathlib import Path

import numpy as np

from usar_arm import Arm
from usar_arm.core.spatial import rpy_to_matrix, transform

HERE = Path(__file__).resolve().parent
UR5 = HERE / "robots" / "example-robot-data" / "robots" / "ur_description"
arm = Arm.from_files(UR5 / "urdf" / "ur5_robot.urdf", srdf=UR5 / "srdf" / "ur5.srdf", tip="ee_link")
print("planned joints:", ", ".join(arm.joint_names))

# ee_link 45 cm in front, 30 cm to the side, 20 cm up, its x axis (the tool's) pointing down.
pose = transform(rpy_to_matrix((0.0, np.pi / 2, 0.0)), (0.45, 0.30, 0.20))
start = np.array([-1.2, -1.2, 1.2, -1.57, -1.57, 0.0])
solution = arm.ik(pose, seed=start).best.q
reached = arm.fk(np.array(solution))
error = float(np.linalg.norm(reached[:3, 3] - pose[:3, 3]))
print(f"IK, {arm.robot.ik_solver().method}: position error (m): {error:.2g}")

# From the start, over the post between it and the goal.
plan = arm.plan(pose=pose, start=start, scene=HERE / "robots" / "ur5_cell.yaml")
print(f"planned around the post in {plan.planning_seconds * 1000:.0f} ms: "
      f"{len(plan.waypoints)} waypoints, {plan.trajectory.duration:.2f} s of motion")
