"""Plan collision-free, jerk-limited motions: PTP (joint space, sampling-based) and LIN (a
straight tool line), timed with Ruckig, and save the trajectory for `usar-arm execute` or
`usar-arm plot`.

Offline: planning needs only the description.
"""

from pathlib import Path
from tempfile import mkdtemp

import numpy as np

from usar_arm import Arm
from usar_arm.arm.cycle import tcp_offset
from usar_arm.core.spatial import invert, rpy_to_matrix, transform

HERE = Path(__file__).resolve().parent
arm = Arm.from_files(HERE.parent / "robots" / "generated" / "KR60.urdf")
down = rpy_to_matrix((0.0, np.pi, 0.0))
# Poses are tool0's; the KR60 carries a vacuum gripper, so aim its suction cup (the TCP) and
# take tool0 from it through the description's tool0 -> TCP transform.
tcp = tcp_offset(arm.robot)


def cup_at(x: float, y: float, z: float) -> np.ndarray:
    """tool0's pose that puts the suction cup at (x, y, z) m, pointing down."""
    return transform(down, (x, y, z)) @ invert(tcp)


# PTP from home to above the part on the table, around the obstacles.
above = cup_at(1.45, -0.45, 1.10)
ptp = arm.plan(pose=above, scene="table", start=arm.home, speed_scale=0.5)
print(f"PTP: planned in {ptp.planning_seconds * 1000:.1f} ms, "
      f"{ptp.trajectory.duration:.2f} s of motion, {len(ptp.waypoints)} waypoints")

# LIN straight down 28 cm, the cup to 2 cm over the part's top, starting where the PTP ends.
at_part = cup_at(1.45, -0.45, 0.82)
lin = arm.plan(pose=at_part, motion="lin", scene="table", start=ptp.goal)
cup = np.array([(arm.fk(q) @ tcp)[:3, 3] for q in lin.trajectory.q])
off_line = np.linalg.norm(cup[:, :2] - np.array([1.45, -0.45]), axis=1).max()
print(f"LIN: {lin.trajectory.duration:.2f} s; the cup stays within "
      f"{off_line * 1e6:.2f} um of the vertical line")

# Around the tower to above the bin: the planner finds a path with several waypoints. A
# blended PTP passes them without stopping (and is re-checked for collisions and limits).
above_bin = cup_at(1.45, 0.50, 1.10)
stop = arm.plan(pose=above_bin, scene="table", start=ptp.goal)
blend = arm.plan(pose=above_bin, scene="table", start=ptp.goal, blend=True)
print(f"around the tower: {len(stop.waypoints)} waypoints, {stop.trajectory.duration:.2f} s "
      f"stopping at each, {blend.trajectory.duration:.2f} s blended")

out = Path(mkdtemp(prefix="plans-")) / "ptp.json"
ptp.trajectory.save(out)
print("wrote", out, f"({len(ptp.trajectory.t)} samples at {ptp.trajectory.rate:.0f} Hz)")
