"""IK with mplib 0.2.1 (Planner.IK): python run_mplib_ik.py PROBLEMS.json RESULTS.json

Planner(urdf, move_group=tip_link, srdf=<problem "srdf", else mplib's own lookup: <urdf>.srdf
beside the URDF, else it generates one>). Timed: planner.IK(Pose(xyz, quat_wxyz), seed,
threshold=position_m + orientation_rad/2) with the defaults otherwise: n_init_qpos=20 CLIK
runs (the seed, then 19 random starts; it does NOT stop at the first success), each checked
for joint limits and collisions; mplib's threshold is ||dp|| + ||dq_quat|| and a quaternion
difference norm is ~angle/2. mplib has no timeout. "all_q": the distinct solutions found;
"q": the one nearest the seed (picked after the timed call). RNG: mplib.set_global_seed(1)
(0 is refused).

A problem file's "urdf_mplib" (the robots stage), when present, is read instead of "urdf": the
same URDF text with mesh paths relative to its folder (mplib joins every mesh path to the
URDF's folder, an absolute one included).
"""

import mplib
import numpy as np
import peerio
from mplib import Planner, Pose

spec, out = peerio.args()
tol = spec["tolerance"]
threshold = tol["position_m"] + tol["orientation_rad"] / 2
kw = {"srdf": spec["srdf"]} if spec.get("srdf") else {}
planner = Planner(urdf=spec.get("urdf_mplib") or spec["urdf"], move_group=spec["tip_link"], **kw)
mplib.set_global_seed(1)
idx = planner.move_group_joint_indices
mp_names = [planner.user_joint_names[i] for i in idx]
names = spec["joint_names"]
if len(idx) != len(planner.user_joint_names):
    raise SystemExit("the robot has joints outside the move group; padding is not handled")


def solve(p):
    goal = Pose(p=np.array(p["xyz"], float), q=np.array(p["quat_wxyz"], float))
    seed = np.array(peerio.reorder(p["seed"], names, mp_names), float)
    (status, qs), sec = peerio.timed(planner.IK, goal, seed, threshold=threshold)
    ok = status == "Success"
    all_q = [peerio.reorder(q[idx], mp_names, names) for q in qs] if ok else []
    r = {"success": ok, "seconds": sec, "q": peerio.nearest(all_q, p["seed"]), "all_q": all_q}
    return r if ok else {**r, "status": status}


peerio.write(
    out,
    peer="mplib",
    dist="mplib",
    stage="ik",
    results=peerio.solve_all(spec["problems"], solve),
    settings={"threshold": threshold, "n_init_qpos": 20},
    notes="Planner.IK always runs 20 CLIK starts and checks collisions",
)
