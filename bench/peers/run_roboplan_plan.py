"""Motion planning with roboplan 0.7.0: python run_roboplan_plan.py PROBLEMS.json RESULTS.json

Scene("robot", loadUrdfSceneDescription(urdf)) + importSrdf(<problem "srdf", else the .srdf
beside the URDF>) (see rp_scene.py). Obstacles (rp_scene.Obstacles):
scene.addBoxGeometry / addCylinderGeometry / addSphereGeometry / addMeshGeometry(name, "universe",
shape, T, rgba), added once per scene, removed (removeGeometry) before the next, "allow" links
exempted with setCollisions(name, link, False); the RRT and the shortcutter are rebuilt after
each scene change (untimed).

Timed ("seconds"): RRT(scene, RRTOptions(group_name, rrt_connect=True,
max_planning_time=time_limit_s)).plan(start, goal) + PathShortcutter(scene,
PathShortcuttingOptions(group_name, seed=problem seed)).shortcut(path); other options are
roboplan's defaults (max_nodes=1000, max_connection_distance=3.0, collision_check_step_size=0.05,
shortcut max_step_size=0.05, max_iters=100). rrt.setRngSeed(problem seed) before each plan.
"duration_s": PathParameterizerTOPPRA(scene, group).generate(path, TOPPRAOptions(dt=0.01)),
untimed in "seconds" (its own "topp_seconds"), only when the problem file has vmax and amax
(the URDF has no accelerations); its default spline mode (Hermite) stops at every waypoint.
"""

import tempfile
import time
from pathlib import Path

import numpy as np
import peerio
import rp_scene
from roboplan import core
from roboplan.rrt import RRT, RRTOptions
from roboplan.toppra import PathParameterizerTOPPRA, TOPPRAOptions

spec, out = peerio.args()
names = spec["joint_names"]
scene, group, rp_names, acm = rp_scene.load(spec)
topp = None
if spec.get("vmax") is not None and spec.get("amax") is not None:
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        f.write(peerio.joint_limits_yaml(names, spec["vmax"], spec["amax"]))
    scene.importJointLimitsFromConfig(core.loadJointLimitsConfig(f.name))
    Path(f.name).unlink()
    topp = PathParameterizerTOPPRA(scene, group)
planner = {}


def rebuild(_name):
    planner["rrt"] = RRT(
        scene,
        RRTOptions(group_name=group, rrt_connect=True, max_planning_time=spec["time_limit_s"]),
    )


obstacles = rp_scene.Obstacles(scene, spec["scenes"], on_change=rebuild)


def solve(p):
    seed = int(p.get("seed", 0))
    rrt = planner["rrt"]
    rrt.setRngSeed(seed)
    shortcutter = core.PathShortcutter(
        scene, core.PathShortcuttingOptions(group_name=group, seed=seed)
    )
    start = core.JointConfiguration(rp_names, np.array(peerio.reorder(p["start"], names, rp_names)))
    goal = core.JointConfiguration(rp_names, np.array(peerio.reorder(p["goal"], names, rp_names)))
    t0 = time.perf_counter()
    try:
        path = rrt.plan(start, goal)
    except RuntimeError as e:  # roboplan reports planning failures as exceptions
        return {
            "success": False,
            "seconds": time.perf_counter() - t0,
            "path": None,
            "status": str(e),
        }
    t_rrt = time.perf_counter() - t0
    short, t_short = peerio.timed(shortcutter.shortcut, path)
    r = {
        "success": True,
        "seconds": t_rrt + t_short,
        "rrt_seconds": t_rrt,
        "shortcut_seconds": t_short,
        "rrt_waypoints": len(path.positions),
        "path": [peerio.reorder(q, short.joint_names, names) for q in short.positions],
    }
    if topp is not None:
        try:
            traj, topp_sec = peerio.timed(topp.generate, short, TOPPRAOptions(dt=0.01))
            r.update(duration_s=float(traj.times[-1]), topp_seconds=topp_sec)
        except Exception as e:
            r.update(duration_s=None, topp_error=f"{type(e).__name__}: {e}")
    return r


peerio.write(
    out,
    peer="roboplan",
    dist="roboplan",
    stage="plan",
    results=peerio.solve_by_scene(spec["problems"], obstacles.enter, solve),
    notes="seconds = RRT-Connect + PathShortcutter.shortcut; duration_s from roboplan's "
    "TOPP-RA (Hermite mode, zero velocity at each waypoint), timed separately",
)
