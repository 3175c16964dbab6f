"""Motion planning with VAMP: python run_vamp_plan.py PROBLEMS.json RESULTS.json

VAMP (KavrakiLab/vamp, "Motions in Microseconds via Vectorized Sampling-Based Planning") is a
C++ planner with Python bindings that plans for robots compiled into it, on their sphere models:
here the problem file's ``robot`` (``panda`` or ``ur5``: robowflex's models, the ones
MotionBenchMaker's problems were made for, not the meshes the other solvers load; the file's
obstacles are in the scene's frame, the frame VAMP's models stand in).

Set-up (untimed), as VAMP's own ``scripts/evaluate_mbm.py`` does:
``vamp.configure_robot_and_planner_with_kwargs(robot, "rrtc")`` (RRT-Connect, its default
settings: dynamic domain, the robot's range, 10^6 iterations and samples; the simplification's
defaults), ``module.halton()`` as the sampler. Obstacles per scene as
``vamp.problem_dict_to_vamp`` builds them from MBM's files: a box a ``Cuboid(centre, euler xyz,
half extents)``, a sphere a ``Sphere``, a cylinder a capsule (``add_capsule(Cylinder(...))``,
which covers it), except in MBM's ``box`` set, whose cylinders VAMP covers by a cuboid (its
top-down grasp does not fit a capsule's rounded end).

Per problem ``sampler.reset()`` (each problem's answer is the same whatever came before it);
then timed: ``planner(start, goal, env, settings, sampler)`` and, when solved,
``module.simplify(path, env, simplify_settings, sampler)``. ``seconds`` is the wall time of
those two Python calls (``time.perf_counter``; VAMP allocates its search buffers for 10^6
samples in every call); ``own_seconds`` is VAMP's own timer, the sum of the two results'
``nanoseconds`` (what its benchmark reports), ``plan_own_seconds`` and
``simplify_own_seconds`` its parts, ``iterations`` the planner's. ``path``: the simplified
path's waypoints (VAMP's float32 values, start first, goal last), in the file's joint order.
"""

import time

import numpy as np
import peerio
import vamp
from vamp import transformations as vt

spec, out = peerio.args()
robot = spec["robot"]
module, planner, plan_settings, simplify_settings = (
    vamp.configure_robot_and_planner_with_kwargs(robot, "rrtc"))
sampler = module.halton()
names = spec["joint_names"]
vamp_names = list(module.joint_names())[:len(names)]
if sorted(vamp_names) != sorted(names):
    raise SystemExit(f"VAMP's {robot} joints {vamp_names} are not the file's {names}")
state = {}


def _euler(quat_wxyz):
    """Euler angles (rad, static x-y-z, VAMP's convention) of a (w, x, y, z) quaternion."""
    m = np.eye(4)
    m[:3, :3] = peerio.quat_to_matrix(quat_wxyz)
    return [float(a) for a in vt.euler_from_matrix(m)]


def environment(scene_name):
    """VAMP's environment of one scene (its MBM set named before the slash)."""
    env = vamp.Environment()
    box_set = scene_name.split("/")[0] == "box"
    for o in spec["scenes"][scene_name]:
        centre = [float(v) for v in o["xyz"]]
        euler = _euler(o.get("quat_wxyz", [1.0, 0.0, 0.0, 0.0]))
        if o["type"] == "box":
            env.add_cuboid(vamp.Cuboid(centre, euler, [float(v) / 2 for v in o["size"]]))
        elif o["type"] == "sphere":
            env.add_sphere(vamp.Sphere(centre, float(o["radius"])))
        elif o["type"] == "cylinder" and box_set:
            r, half = float(o["radius"]), float(o["length"]) / 2
            env.add_cuboid(vamp.Cuboid(centre, euler, [r, r, half]))
        elif o["type"] == "cylinder":
            env.add_capsule(vamp.Cylinder(centre, euler, float(o["radius"]), float(o["length"])))
        else:
            raise ValueError(f"unsupported obstacle type {o['type']!r}")
    return env


def enter(scene_name):
    state["env"] = environment(scene_name)


def solve(p):
    env = state["env"]
    start = peerio.reorder(p["start"], names, vamp_names)
    goal = peerio.reorder(p["goal"], names, vamp_names)
    sampler.reset()
    t0 = time.perf_counter()
    result = planner(start, goal, env, plan_settings, sampler)
    if not result.solved:
        return {"success": False, "seconds": time.perf_counter() - t0, "path": None,
                "own_seconds": result.nanoseconds * 1e-9, "iterations": result.iterations,
                "status": "not solved within VAMP's iteration limit"}
    simple = module.simplify(result.path, env, simplify_settings, sampler)
    seconds = time.perf_counter() - t0
    path = simple.path.numpy().astype(float)
    return {"success": True, "seconds": seconds,
            "own_seconds": (result.nanoseconds + simple.nanoseconds) * 1e-9,
            "plan_own_seconds": result.nanoseconds * 1e-9,
            "simplify_own_seconds": simple.nanoseconds * 1e-9,
            "iterations": result.iterations, "rrt_waypoints": len(result.path),
            "path": [peerio.reorder(q, vamp_names, names) for q in path.tolist()]}


peerio.write(
    out, peer="vamp", dist="vamp-planner", stage="plan",
    results=peerio.solve_by_scene(spec["problems"], enter, solve),
    settings={"robot": robot, "planner": "rrtc", "sampler": "halton, reset per problem",
              "range": float(plan_settings.range),
              "max_iterations": int(plan_settings.max_iterations)},
    notes="seconds = the wall time of VAMP's planner and simplify calls from Python; "
    "own_seconds = VAMP's own timer (the results' nanoseconds); VAMP checks its sphere model "
    "of robowflex's robot, not the meshes the judge checks",
)
