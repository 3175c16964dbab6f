"""Calibration from a laser-tracker file: what a real robot's owner does with a tracker.

The embedded simulator plays the tracker here: the arm (described as learnt over the UDK wire,
2-3 mm off at the tool) visits 25 poses; at each, tool0's true pose in base_link (the
simulator's own geometry, as a tracker would measure it) gets 0.05 mm / 0.05 mrad of noise, and
the joint values are the ones the server printed (at the middle of their 1e-4 rad steps).
The readings go to a CSV in millimetres and degrees (examples/calibration/kr60-tracker.csv is
one such file), and `usar-arm calibrate --measurements` fits the as-learnt URDF to them.
"""

import sys
import time
from pathlib import Path

import numpy as np

from usar_arm import Arm
from usar_arm.calibrate.measurement_writer import write_measurements
from usar_arm.calibrate.measurements import Measurement, MeasurementSet
from usar_arm.calibrate.observability import select_poses
from usar_arm.cli.main import main
from usar_arm.core.spatial import matrix_to_rpy
from usar_arm.usarsim.numbers import truncated_midpoint

POSES = 25


def joints(arm: Arm) -> np.ndarray:
    """The joint values the server printed, each at the middle of the step it was truncated to
    (a robot controller would report its encoders' values)."""
    return np.array(truncated_midpoint(tuple(arm.joints()), arm.joint_step()))


def tool0_now(arm: Arm, port: int) -> np.ndarray:
    """tool0's true pose in base_link now (the simulator's own geometry: what a tracker sees)."""
    assert arm.server is not None
    truth = arm.server.truth(port)
    assert truth is not None
    return truth.tool0[str(arm.robot.actuator)]


NOISE_M, NOISE_RAD = 5e-5, 5e-5
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("tracker-example")
rng = np.random.default_rng(7)
readings = []
CELL = "table"  # the embedded simulator's world: the demo's work cell, which the arm must avoid

with Arm.connect("KR60", calibrated=False) as arm:
    world = arm.robot.collision_world(arm.world(CELL).scene, padding=0.05)  # 5 cm clear
    poses = select_poses(arm.urdf, "tool0", POSES, lambda q: not world.in_collision(q), seed=7)
    for k, q in enumerate(poses):
        arm.execute(arm.plan(joints=q, scene=CELL).trajectory)
        port = arm.client.local_port if arm.client else None
        assert arm.server is not None and port, "the tracker example needs the embedded simulator"

        # A tracker measures the arm at rest: wait until tool0 stays put (0.1 um over 0.2 s)
        # across a reading of the joints, so both are of the same still arm (a busy machine
        # lets the drives creep for a while after the motion's end).
        for _ in range(50):
            before = tool0_now(arm, port)
            time.sleep(0.2)
            q_read = joints(arm)
            tool0 = tool0_now(arm, port)
            if np.abs(tool0 - before).max() < 1e-7:
                break
        noisy_rpy = np.array(matrix_to_rpy(tool0[:3, :3])) + rng.normal(0.0, NOISE_RAD, 3)
        readings.append(Measurement(q=q_read, position=tool0[:3, 3]
                                    + rng.normal(0.0, NOISE_M, 3), rpy=noisy_rpy,
                                    sigma_m=NOISE_M, sigma_rad=NOISE_RAD, label=f"pose {k}"))
        print(f"pose {k + 1}/{POSES} measured", flush=True)
    urdf = out / "KR60.urdf"
    out.mkdir(parents=True, exist_ok=True)
    urdf.write_text(arm.urdf)
data = MeasurementSet(tuple(readings), "tool0", joint_names=arm.joint_names)
write_measurements(out / "kr60-tracker.csv", data, length_unit="mm", angle_unit="deg")
print(f"wrote {out / 'kr60-tracker.csv'}")
sys.exit(main(["calibrate", "--measurements", str(out / "kr60-tracker.csv"), "--urdf",
               str(urdf), "--out-dir", str(out / "calibrated")]))
