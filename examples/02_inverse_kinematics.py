"""Inverse kinematics: the joint values that put tool0 at a pose.

The KR60 is ortho-parallel, so usar-arm solves it analytically (all eight branches, polished
by Newton steps on the exact model); other arms get a numeric solver. Offline: the description
is read from files, no server needed.
"""

from pathlib import Path

import numpy as np

from usar_arm import Arm
from usar_arm.core.spatial import rpy_to_matrix, transform

HERE = Path(__file__).resolve().parent
arm = Arm.from_files(HERE.parent / "robots" / "generated" / "KR60.urdf")

# tool0 1.2 m in front of the robot, 1.3 m up, pointing forward and down.
pose = transform(rpy_to_matrix((0.0, 2.5, 0.3)), (1.2, 0.3, 1.3))

nearest = arm.ik(pose, seed=arm.home)  # the solution closest to a seed
q = nearest.best.q
print("nearest to home (rad):", np.round(q, 4))

reached = arm.fk(np.array(q))
print("position error (m):", np.linalg.norm(reached[:3, 3] - pose[:3, 3]))

everything = arm.ik(pose, all_solutions=True)  # every branch within the joint limits
print(f"{len(everything.solutions)} solutions (shoulder, elbow, wrist branches):")
for solution in everything.solutions:
    print("  ", np.round(solution.q, 3))

# Solutions that collide with the table scene's obstacles are dropped.
free = arm.ik(pose, all_solutions=True, scene="table")
print(f"{len(free.solutions)} of them are collision-free in the table scene")
