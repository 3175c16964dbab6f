"""Motion planning with mplib 0.2.1: python run_mplib_plan.py PROBLEMS.json RESULTS.json

Planner(urdf, move_group=tip_link, srdf=srdf, joint_vel_limits=vmax, joint_acc_limits=amax)
(limits only when the problem file has them: mplib's default is 1 rad/s and 1 rad/s^2). Scene
obstacles (mp_scene.py): planning_world.add_object(name, fcl.CollisionObject(fcl.Box/Cylinder/
Sphere/BVH mesh, Pose(xyz, quat_wxyz))), added once per scene and removed before the next scene;
an obstacle's "allow" links are allowed to touch it (allowed-collision matrix).

Planner.plan_qpos() = OMPL RRTConnect + simplification (planner.planner.plan) followed by
TOPP-RA (planner.TOPP); this runner makes those two calls itself, as plan_qpos does (start
clipped to the limits, range=0.1, simplify=True; time = time_limit_s), so that "seconds" is
planning + simplification alone; "topp_seconds" and "duration_s" come from the following
planner.TOPP(path, step=0.01). RNG: mplib.set_global_seed(problem seed) before each problem.

A problem file's "attached" objects (the carry stage: type and sizes, xyz and quat_wxyz in the
frame of their "link", "touch_links") are attached with planning_world.attach_object(name,
geometry, robot, link index, pose, touch_links), MPlib's attached body (update_attached_box
attaches to the move group's link only), and a scene object of the same name is left out.

A problem file's "urdf_mplib" (the robots stage), when present, is read instead of "urdf": the
same URDF text with mesh paths relative to its folder (mplib joins every mesh path to the
URDF's folder, an absolute one included).
"""

import mp_scene
import mplib
import numpy as np
import peerio
from mplib import Planner, Pose

spec, out = peerio.args()
names = spec["joint_names"]
limits = {
    k: v
    for k, v in (("joint_vel_limits", spec.get("vmax")), ("joint_acc_limits", spec.get("amax")))
    if v is not None
}
planner = Planner(
    urdf=spec.get("urdf_mplib") or spec["urdf"],
    move_group=spec.get("tip_link", "tool0"),
    srdf=spec.get("srdf"),
    **limits,
)
idx = planner.move_group_joint_indices
mp_names = [planner.user_joint_names[i] for i in idx]
if len(idx) != len(planner.user_joint_names):
    raise SystemExit("the robot has joints outside the move group; padding is not handled")
carried = spec.get("attached", [])
held = {item["name"] for item in carried}
obstacles = mp_scene.Obstacles(  # (a scene object of a carried object's name is that object)
    planner, {k: [o for o in v if o.get("name") not in held] for k, v in spec["scenes"].items()}
)
for item in carried:  # MPlib's attached object: fixed to the link, its touch links allowed
    planner.planning_world.attach_object(
        item["name"],
        mp_scene.shape(item),
        planner.robot.get_name(),
        planner.user_link_names.index(item["link"]),
        Pose(p=np.array(item["xyz"], float), q=np.array(item["quat_wxyz"], float)),
        list(item.get("touch_links", [])),
    )


def solve(p):
    start = np.array(peerio.reorder(p["start"], names, mp_names), float)
    start = np.clip(
        start, planner.joint_limits[idx, 0], planner.joint_limits[idx, 1]
    )  # as plan_qpos
    goal = np.array(peerio.reorder(p["goal"], names, mp_names), float)
    mplib.set_global_seed(int(p.get("seed", 1)) or 1)
    planner.robot.set_qpos(start, True)
    (status, path), sec = peerio.timed(
        planner.planner.plan, start, [goal], time=spec["time_limit_s"], range=0.1, simplify=True
    )
    if status != "Exact solution":
        return {"success": False, "seconds": sec, "path": None, "status": status}
    path = np.asarray(path)
    r = {
        "success": True,
        "seconds": sec,
        "path": [peerio.reorder(q, mp_names, names) for q in path],
    }
    if not np.allclose(path[0], start, atol=1e-9):  # OMPL perturbs an invalid start state
        r["start_moved"] = True
    try:
        (_, _, _, _, duration), topp_sec = peerio.timed(planner.TOPP, path, 0.01)
        r.update(duration_s=float(duration), topp_seconds=topp_sec)
    except Exception as e:
        r.update(duration_s=None, topp_error=f"{type(e).__name__}: {e}")
    return r


peerio.write(
    out,
    peer="mplib",
    dist="mplib",
    stage="carry" if carried else "plan",
    results=peerio.solve_by_scene(spec["problems"], obstacles.enter, solve),
    notes="seconds = OMPL RRTConnect + path simplification (planner.planner.plan); "
    "duration_s from planner.TOPP (TOPP-RA on a spline through the path, "
    + ("problem vmax/amax" if limits else "mplib default limits 1 rad/s, 1 rad/s^2")
    + "), timed separately as topp_seconds",
)
