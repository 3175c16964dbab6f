"""Connect to a USARSim server, spawn a KR60 and learn its description.

Without a host, usar-arm starts its embedded simulator in this process. Discovery reads the
arm's CONF and GEO replies and builds the URDF, SRDF and joint limits (cached, so a second run
of the same arm is instant). Pass a host to use a real USARSim: Arm.connect("KR60", "10.0.0.5").
"""

from pathlib import Path
from tempfile import mkdtemp

import numpy as np

from usar_arm import Arm

with Arm.connect("KR60") as arm:
    print("joints:", ", ".join(arm.joint_names))
    print("USARSim actuator:", arm.robot.actuator, "| tip sensor:", arm.robot.tip_sensor)
    for name, limit in zip(arm.joint_names, arm.robot.chain.limits(), strict=True):
        print(f"  {name:<9} [{limit.lower:+.3f}, {limit.upper:+.3f}] rad, "
              f"up to {limit.velocity:.2f} rad/s")

    q = arm.joints()  # the arm's current joint values, from its ASTA messages
    print("current joints (rad):", np.round(q, 4))

    tool = arm.fk(q)  # tool0 in base_link (REP-103: x forward, z up), 4x4
    print("tool0 at (m):", np.round(tool[:3, 3], 4))

    folder = Path(mkdtemp(prefix="kr60-description-"))
    for path in arm.write_description(folder):
        print("wrote", path)
