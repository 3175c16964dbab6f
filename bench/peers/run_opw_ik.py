"""Analytic OPW IK (py-opw-kinematics 1.3.0): python run_opw_ik.py PROBLEMS.json RESULTS.json

Needs the problem file's "opw" block: a1, a2, b, c1, c2, c3, c4 (m), "offsets" (6, rad) and
"flip_axes" (6 bools) or "sign_corrections" (6 x +-1, -1 = flipped); optional "base_pose" (the
OPW base frame in base_link) and "tool_pose" (tip_link in OPW's end frame), each
{"xyz", "quat_wxyz"}, identity when absent. Without an "opw" block every result is an error.

Solver: Robot(KinematicModel(...), degrees=False). Timed: Robot.inverse(pose, current_joints=seed)
alone (the target's change of frame is done before). "all_q": every branch the peer returns;
"q": the branch nearest the seed among those inside [lower, upper]; success: such a branch
exists. The peer knows nothing of joint limits or collisions.
"""

import numpy as np
import peerio
from py_opw_kinematics import KinematicModel, Robot
from scipy.spatial.transform import RigidTransform

spec, out = peerio.args()
o = spec.get("opw")
lo, hi = np.array(spec["lower"]), np.array(spec["upper"])


def frame(key):
    f = (o or {}).get(key)
    return np.eye(4) if f is None else peerio.pose_matrix(f["xyz"], f["quat_wxyz"])


if o:
    flips = o.get("flip_axes")
    if flips is None:
        flips = [s < 0 for s in o.get("sign_corrections", [1] * 6)]
    model = KinematicModel(
        a1=o["a1"],
        a2=o["a2"],
        b=o["b"],
        c1=o["c1"],
        c2=o["c2"],
        c3=o["c3"],
        c4=o["c4"],
        offsets=tuple(o.get("offsets", [0.0] * 6)),
        flip_axes=tuple(bool(f) for f in flips),
    )
    robot = Robot(model, degrees=False)
    base_inv, tool_inv = np.linalg.inv(frame("base_pose")), np.linalg.inv(frame("tool_pose"))


def solve(p):
    if not o:
        raise ValueError("no 'opw' parameters in the problem file")
    target = base_inv @ peerio.pose_matrix(p["xyz"], p["quat_wxyz"]) @ tool_inv
    pose = RigidTransform.from_matrix(target)
    seed = tuple(float(v) for v in p["seed"])
    sols, sec = peerio.timed(robot.inverse, pose, current_joints=seed)
    sols = [list(map(float, s)) for s in sols]
    inside = [
        s for s in sols if np.all(np.array(s) >= lo - 1e-9) and np.all(np.array(s) <= hi + 1e-9)
    ]
    q = peerio.nearest(inside, p["seed"])
    return {
        "success": q is not None,
        "seconds": sec,
        "q": q,
        "all_q": sols,
        "n_in_limits": len(inside),
    }


peerio.write(
    out,
    peer="opw",
    dist="py-opw-kinematics",
    stage="ik",
    results=peerio.solve_all(spec["problems"], solve),
    notes="analytic; q = branch nearest the seed within limits; approximate when the "
    "arm is only nearly ortho-parallel",
)
