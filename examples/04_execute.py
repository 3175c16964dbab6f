"""Execute a motion on the arm: ACT commands streamed at 100 Hz, ASTA feedback watched, the
final tool0 error measured with the tip GroundTruth sensor.

The first execution learns each drive's response (a 2 s swing) for feedforward.
"""

import numpy as np

from usar_arm import Arm
from usar_arm.core.errors import ExecutionAbortedError
from usar_arm.core.spatial import rpy_to_matrix, transform

target = transform(rpy_to_matrix((0.0, np.pi, 0.0)), (1.3, 0.2, 1.2))

with Arm.connect("KR60") as arm:
    plan = arm.plan(pose=target, scene="table")  # from the arm's current joints
    report = arm.execute(plan.trajectory, goal_pose=target)
    print(f"{report.rate_hz:.1f} Hz, p99 jitter {report.jitter_p99_ms:.2f} ms")
    print(f"max tracking error {report.max_tracking_error_rad * 1000:.2f} mrad")
    print(f"final joint error {np.max(report.final_joint_error_rad):.5f} rad")
    if report.tip is not None:
        print(f"tool0 error {report.tip.error_m * 1000:.2f} mm ({report.tip.source})")

    # A motion that cannot be tracked is stopped, and the arm holds where it is.
    from usar_arm.control.executor import ExecutionOptions

    back = arm.plan(joints=arm.home)
    try:
        arm.execute(back.trajectory, options=ExecutionOptions(max_tracking_error=1e-4,
                                                             feedforward=False))
    except ExecutionAbortedError as stop:
        print("stopped:", stop)
    arm.executor(ExecutionOptions())  # back to the default options
    home = arm.plan(joints=arm.home)
    print("back home, settled:", arm.execute(home.trajectory).settled)
