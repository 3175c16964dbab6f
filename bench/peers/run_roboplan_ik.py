"""IK with roboplan 0.7.0 (SimpleIk): python run_roboplan_ik.py PROBLEMS.json RESULTS.json

Scene("robot", loadUrdfSceneDescription(urdf)) + importSrdf(<problem "srdf", else the .srdf
beside the URDF>) (see rp_scene.py). SimpleIk(scene, SimpleIkOptions(group_name, max_time=timeout_s,
max_linear_error_norm=position_m, max_angular_error_norm=orientation_rad)), defaults
otherwise (max_iters=100, max_restarts=2, step_size=0.25, damping=1e-3, check_collisions=True,
fast_return=True). Timed: ik.solveIk(CartesianConfiguration(base, tip, T), JointConfiguration
(names, seed), solution) alone. With ROBOPLAN_IK_CHECK_COLLISIONS=0 in the environment
(run_roboplan_ik_unchecked.py), check_collisions=False: the mode without a collision check.
"""

import os

import numpy as np
import peerio
import rp_scene
from roboplan import core
from roboplan.simple_ik import SimpleIk, SimpleIkOptions

spec, out = peerio.args()
tol = spec["tolerance"]
scene, group, rp_names, acm = rp_scene.load(spec)
opts = SimpleIkOptions(
    group_name=group,
    max_time=spec["timeout_s"],
    max_linear_error_norm=tol["position_m"],
    max_angular_error_norm=tol["orientation_rad"],
    check_collisions=os.environ.get("ROBOPLAN_IK_CHECK_COLLISIONS", "1") != "0",
)
ik = SimpleIk(scene, opts)
ik.setRngSeed(0)
names = spec["joint_names"]


def solve(p):
    goal = core.CartesianConfiguration(
        spec["base_link"], spec["tip_link"], peerio.pose_matrix(p["xyz"], p["quat_wxyz"])
    )
    start = core.JointConfiguration(rp_names, np.array(peerio.reorder(p["seed"], names, rp_names)))
    sol = core.JointConfiguration()
    ok, sec = peerio.timed(ik.solveIk, goal, start, sol)
    return {
        "success": bool(ok),
        "seconds": sec,
        "q": peerio.reorder(sol.positions, sol.joint_names, names) if ok else None,
    }


peerio.write(
    out,
    peer="roboplan",
    dist="roboplan",
    stage="ik",
    results=peerio.solve_all(spec["problems"], solve),
    settings={"group": group, "max_time": spec["timeout_s"], "collisions": acm,
              "check_collisions": opts.check_collisions},
    notes="SimpleIk" + (" checks collisions (SRDF pairs disabled)" if opts.check_collisions
                        else " without its collision check"),
)
