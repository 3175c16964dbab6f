"""Collision checks with mplib 0.2.1: python run_mplib_collision.py PROBLEMS.json RESULTS.json

Planner(urdf, move_group=tip_link, srdf=srdf) (SRDF pairs disabled); scene obstacles as in the
plan runner (mp_scene.py). Timed per configuration: planner.robot.set_qpos(q, True) (forward
kinematics, collision-object poses) + planner.planning_world.is_state_colliding() (self and
environment; FCL). Result per problem: "collision" (bool).

A problem file's "urdf_mplib" (the robots stage), when present, is read instead of "urdf": the
same URDF text with mesh paths relative to its folder (mplib joins every mesh path to the
URDF's folder, an absolute one included).
"""

import mp_scene
import numpy as np
import peerio
from mplib import Planner

spec, out = peerio.args()
names = spec["joint_names"]
planner = Planner(
    urdf=spec.get("urdf_mplib") or spec["urdf"],
    move_group=spec.get("tip_link", "tool0"),
    srdf=spec.get("srdf"),
)
idx = planner.move_group_joint_indices
mp_names = [planner.user_joint_names[i] for i in idx]
if len(idx) != len(planner.user_joint_names):
    raise SystemExit("the robot has joints outside the move group; padding is not handled")
obstacles = mp_scene.Obstacles(planner, spec["scenes"])
robot, world = planner.robot, planner.planning_world


def check(q):
    robot.set_qpos(q, True)
    return world.is_state_colliding()


def solve(p):
    q = np.array(peerio.reorder(p["q"], names, mp_names), float)
    hit, sec = peerio.timed(check, q)
    return {"success": True, "seconds": sec, "collision": bool(hit)}


peerio.write(
    out,
    peer="mplib",
    dist="mplib",
    stage="collision",
    results=peerio.solve_by_scene(spec["problems"], obstacles.enter, solve, warmup=3),
    notes="seconds = robot.set_qpos(q, True) + planning_world.is_state_colliding()",
)
