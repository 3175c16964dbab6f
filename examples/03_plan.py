"""Plan collision-free, jerk-limited motions: PTP (joint space, OMPL) and LIN (a straight tool
line), timed with Ruckig, and save the trajectory for `usar-arm execute` or `usar-arm plot`.

Offline: planning needs only the description.
"""

from pathlib import Path
from tempfile import mkdtemp

import numpy as np

from usar_arm import Arm
from usar_arm.core.spatial import rpy_to_matrix, transform

HERE = Path(__file__).resolve().parent
arm = Arm.from_files(HERE.parent / "robots" / "generated" / "KR60.urdf")
down = rpy_to_matrix((0.0, np.pi, 0.0))

# PTP from home to above the part on the table, around the obstacles.
above = transform(down, (1.45, -0.45, 1.10))
ptp = arm.plan(pose=above, scene="table", start=arm.home, speed_scale=0.5)
print(f"PTP: planned in {ptp.planning_seconds * 1000:.1f} ms, "
      f"{ptp.trajectory.duration:.2f} s of motion, {len(ptp.waypoints)} waypoints")

# LIN straight down 28 cm to the part, starting where the PTP ends.
at_part = transform(down, (1.45, -0.45, 0.82))
lin = arm.plan(pose=at_part, motion="lin", scene="table", start=ptp.goal)
tool = np.array([arm.fk(q)[:3, 3] for q in lin.trajectory.q])
off_line = np.linalg.norm(tool[:, :2] - at_part[:2, 3], axis=1).max()
print(f"LIN: {lin.trajectory.duration:.2f} s; the tool stays within "
      f"{off_line * 1e6:.2f} um of the vertical line")

# Around the tower to above the bin: OMPL finds a path with several waypoints. A blended
# PTP passes them without stopping (and is re-checked for collisions and limits).
above_bin = transform(down, (1.45, 0.50, 1.10))
stop = arm.plan(pose=above_bin, scene="table", start=ptp.goal)
blend = arm.plan(pose=above_bin, scene="table", start=ptp.goal, blend=True)
print(f"around the tower: {len(stop.waypoints)} waypoints, {stop.trajectory.duration:.2f} s "
      f"stopping at each, {blend.trajectory.duration:.2f} s blended")

out = Path(mkdtemp(prefix="plans-")) / "ptp.json"
ptp.trajectory.save(out)
print("wrote", out, f"({len(ptp.trajectory.t)} samples at {ptp.trajectory.rate:.0f} Hz)")
