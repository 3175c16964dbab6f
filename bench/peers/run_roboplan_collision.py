"""Collision checks with roboplan 0.7.0: python run_roboplan_collision.py PROBLEMS.json RESULTS.json

Scene + SRDF as in rp_scene.load; obstacles as in the plan runner (rp_scene.Obstacles). Timed
per configuration: scene.hasCollisions(q) (Pinocchio FK + coal with roboplan's default
requests). Result per problem: "collision" (bool).
"""

import numpy as np
import peerio
import rp_scene

spec, out = peerio.args()
names = spec["joint_names"]
scene, group, rp_names, acm = rp_scene.load(spec)
full = list(scene.getJointNames())
if sorted(full) != sorted(rp_names):
    raise SystemExit(f"the scene has joints outside the group: {full} vs {rp_names}")
obstacles = rp_scene.Obstacles(scene, spec["scenes"])


def solve(p):
    q = np.array(peerio.reorder(p["q"], names, full), float)
    hit, sec = peerio.timed(scene.hasCollisions, q)
    return {"success": True, "seconds": sec, "collision": bool(hit)}


peerio.write(
    out,
    peer="roboplan",
    dist="roboplan",
    stage="collision",
    results=peerio.solve_by_scene(spec["problems"], obstacles.enter, solve, warmup=3),
    settings={"collisions": acm},
    notes="seconds = scene.hasCollisions(q)",
)
