"""Drive Tesseract on a config folder written by ``usar-arm tesseract-config``.

    bench/.venvs/tesseract/bin/python tests/consumers/tesseract_driver.py REQUEST.json OUT.json

Runs in the Tesseract venv and imports nothing from usar-arm (an independent instrument): it
loads the folder's URDF and SRDF (Tesseract resolves the SRDF's plugin configs itself), and
answers the request with Tesseract alone:

* ``description``: links, joints (type, limits) and the kinematic group's joints;
* ``fk``: the tip's 4x4 pose at each configuration (the group's ``calcFwdKin``);
* ``collisions``: per scene (read from the scene file itself: obstacles added to the
  environment as links fixed to the root, meshes loaded by Tesseract, each ``allow`` pair
  added to the allowed collision matrix), the contact pairs of each
  configuration from the default discrete manager, margin 0, ``ContactTestType_ALL``;
* ``ik``: every solution of the group's default inverse kinematics for each pose, from its seed
  and then from up to ``ik_restarts`` random seeds while none comes back;
* ``plans``: per problem, the task composer pipeline's output path (or its failure).

Lengths in metres, angles in radians; poses are 4x4 matrices in the root frame.
"""

import json
import os
import sys
import time
from pathlib import Path

import numpy as np
import yaml

request = json.loads(Path(sys.argv[1]).read_text())
FOLDER = Path(request["folder"])
os.environ["TESSERACT_RESOURCE_PATH"] = str(FOLDER)

from tesseract_robotics import tesseract_collision as tc  # noqa: E402
from tesseract_robotics import tesseract_command_language as cl  # noqa: E402
from tesseract_robotics import tesseract_common as common  # noqa: E402
from tesseract_robotics import tesseract_environment as te  # noqa: E402
from tesseract_robotics import tesseract_geometry as geo  # noqa: E402
from tesseract_robotics import tesseract_kinematics as tk  # noqa: E402
from tesseract_robotics import tesseract_scene_graph as sg  # noqa: E402
from tesseract_robotics import tesseract_task_composer as tcomp  # noqa: E402

ROBOT, GROUP, TIP = request["robot"], request["group"], request["tip"]


def load() -> te.Environment:
    env = te.Environment()
    ok = env.init(common.FilesystemPath(str(FOLDER / f"{ROBOT}.urdf")),
                  common.FilesystemPath(str(FOLDER / f"{ROBOT}.srdf")),
                  common.GeneralResourceLocator())
    if not ok:
        raise SystemExit("Tesseract could not load the description")
    return env


def isometry(m: list) -> common.Isometry3d:
    return common.Isometry3d(np.asarray(m, dtype=np.float64))


def describe(env: te.Environment) -> dict:
    graph = env.getSceneGraph()
    joints = []
    for name in env.getJointNames():
        j = graph.getJoint(name)
        kinds = {sg.JointType_REVOLUTE: "revolute", sg.JointType_PRISMATIC: "prismatic",
                 sg.JointType_FIXED: "fixed"}
        row = {"name": name, "type": kinds.get(j.type, str(j.type)),
               "parent": str(j.parent_link_name), "child": str(j.child_link_name)}
        if j.limits is not None and j.type in (sg.JointType_REVOLUTE, sg.JointType_PRISMATIC):
            row.update(lower=float(j.limits.lower), upper=float(j.limits.upper),
                       velocity=float(j.limits.velocity), effort=float(j.limits.effort))
        joints.append(row)
    group = env.getKinematicGroup(GROUP)
    return {"links": sorted(str(n) for n in env.getLinkNames()), "joints": joints,
            "group_joints": [str(n) for n in group.getJointNames()],
            "active_links": sorted(str(n) for n in env.getActiveLinkNames())}


def fk(env: te.Environment, qs: list) -> list:
    group = env.getKinematicGroup(GROUP)
    return [group.calcFwdKin(np.asarray(q, dtype=np.float64))[TIP].matrix().tolist() for q in qs]


def _rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll), the scene files' fixed-axis convention."""
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def class_boxes(o: dict, pose: np.ndarray, classes: dict) -> list:
    """A WorldController object (``class``, ``scale``) as boxes: one, or an open container's
    floor and four walls (``<name>/floor``, ``wall_front`` +x, ``wall_back``, ``wall_left`` +y,
    ``wall_right``), from the class's outer size and wall thickness the request gives."""
    spec = classes[o["class"]]
    sx, sy, sz = np.multiply(spec["size"], o.get("scale", [1.0, 1.0, 1.0]))
    if not spec["wall"]:
        return [{"name": o["name"], "pose": pose.tolist(), "allow": o.get("allow", []),
                 "type": "box", "size": [sx, sy, sz]}]
    tx, ty, tz = np.multiply(spec["wall"], o.get("scale", [1.0, 1.0, 1.0]))
    pieces = {"floor": ((0, 0, (tz - sz) / 2), (sx, sy, tz)),
              "wall_front": (((sx - tx) / 2, 0, tz / 2), (tx, sy, sz - tz)),
              "wall_back": (((tx - sx) / 2, 0, tz / 2), (tx, sy, sz - tz)),
              "wall_left": ((0, (sy - ty) / 2, tz / 2), (sx - 2 * tx, ty, sz - tz)),
              "wall_right": ((0, (ty - sy) / 2, tz / 2), (sx - 2 * tx, ty, sz - tz))}
    out = []
    for piece, (centre, size) in pieces.items():
        at = pose.copy()
        at[:3, 3] = pose[:3, 3] + pose[:3, :3] @ np.asarray(centre, float)
        out.append({"name": f"{o['name']}/{piece}", "pose": at.tolist(),
                    "allow": o.get("allow", []), "type": "box", "size": [float(v) for v in size]})
    return out


def read_scene(path: str, classes: dict) -> list:
    """The obstacles of a usar-arm scene file, read here (box, cylinder, sphere, mesh, a
    WorldController class; xyz, rpy, allow), each with its 4x4 pose."""
    doc = yaml.safe_load(Path(path).read_text())
    items = []
    for o in doc.get("objects") or []:
        pose = np.eye(4)
        pose[:3, :3] = _rpy(*o.get("rpy", [0.0, 0.0, 0.0]))
        pose[:3, 3] = o["xyz"]
        if "class" in o:
            items += class_boxes(o, pose, classes)
            continue
        item = {"name": o["name"], "pose": pose.tolist(), "allow": o.get("allow", [])}
        if "box" in o:
            item.update(type="box", size=o["box"])
        elif "cylinder" in o:
            item.update(type="cylinder", **o["cylinder"])
        elif "sphere" in o:
            item.update(type="sphere", **o["sphere"])
        else:
            item.update(type="mesh", file=str(Path(path).parent / o["mesh"]["file"]),
                        scale=float(o["mesh"].get("scale", 1.0)))
        items.append(item)
    return items


def shape(item: dict) -> geo.Geometry:
    kind = item["type"]
    if kind == "box":
        return geo.Box(*item["size"])
    if kind == "cylinder":
        return geo.Cylinder(item["radius"], item["length"])
    if kind == "sphere":
        return geo.Sphere(item["radius"])
    scale = item["scale"]
    return geo.createMeshFromPath(item["file"], np.array([scale, scale, scale]))[0]


def add_scene(env: te.Environment, items: list, root: str) -> None:
    acm = common.AllowedCollisionMatrix()
    for item in items:
        link = sg.Link(item["name"])
        collision = sg.Collision()
        collision.geometry = shape(item)
        link.collision.push_back(collision)
        joint = sg.Joint(f"{item['name']}_joint")
        joint.parent_link_name, joint.child_link_name = root, item["name"]
        joint.type = sg.JointType_FIXED
        joint.parent_to_joint_origin_transform = isometry(item["pose"])
        env.applyCommand(te.AddLinkCommand(link, joint))
        for other in item.get("allow", []):
            acm.addAllowedCollision(item["name"], other, "allowed by the scene")
    env.applyCommand(te.ModifyAllowedCollisionsCommand(acm, te.ModifyAllowedCollisionsType_ADD))


def collisions(qs: list, items: list, root: str) -> dict:
    env = load()
    add_scene(env, items, root)
    names = list(env.getKinematicGroup(GROUP).getJointNames())
    solver = env.getStateSolver()
    manager = env.getDiscreteContactManager()
    manager.setActiveCollisionObjects(env.getActiveLinkNames())
    manager.setCollisionMarginData(common.CollisionMarginData(0.0))
    out, begin = [], time.perf_counter()
    for q in qs:
        solver.setState(names, np.asarray(q, dtype=np.float64))
        state = solver.getState()  # (a temporary's link_transforms would dangle)
        manager.setCollisionObjectsTransform(state.link_transforms)
        result = tc.ContactResultMap()
        manager.contactTest(result, tc.ContactRequest(tc.ContactTestType_ALL))
        flat = tc.ContactResultVector()
        result.flattenMoveResults(flat)
        pairs = {tuple(sorted((flat[i].link_names[0], flat[i].link_names[1])))
                 for i in range(len(flat))}
        out.append(sorted(pairs))
    return {"pairs": out, "seconds": time.perf_counter() - begin,
            "manager": manager.getName()}


def ik(env: te.Environment, problems: list, root: str, restarts: int) -> dict:
    """Each pose from its seed, then (when nothing comes back) from up to ``restarts`` random
    seeds inside the limits, as a user of a local solver does."""
    group = env.getKinematicGroup(GROUP)
    limits = group.getLimits().joint_limits
    rng = np.random.default_rng(0)
    out, attempts, begin = [], [], time.perf_counter()
    for p in problems:
        target = tk.KinGroupIKInput(isometry(p["pose"]), root, TIP)
        seed = np.asarray(p["seed"], dtype=np.float64)
        for attempt in range(restarts + 1):
            solutions = group.calcInvKin(target, seed)
            if len(solutions) or attempt == restarts:
                break
            seed = rng.uniform(limits[:, 0], limits[:, 1])
        attempts.append(attempt + 1)
        out.append([np.asarray(solutions[i]).flatten().tolist() for i in range(len(solutions))])
    return {"solutions": out, "attempts": attempts, "seconds": time.perf_counter() - begin,
            "solver": str(group.getInverseKinematics().getSolverName())}


def plan(env: te.Environment, factory: tcomp.TaskComposerPluginFactory, pipeline: str,
         names: list, start: list, goal: list, root: str) -> dict:
    manip = common.ManipulatorInfo()
    manip.manipulator, manip.working_frame, manip.tcp_frame = GROUP, root, TIP
    program = cl.CompositeInstruction(cl.DEFAULT_PROFILE_KEY, manip,
                                      cl.CompositeInstructionOrder_ORDERED)
    for wp in (cl.StateWaypointPoly_wrap_StateWaypoint(
            cl.StateWaypoint(names, np.asarray(start, dtype=np.float64))),
               cl.JointWaypointPoly_wrap_JointWaypoint(
            cl.JointWaypoint(names, np.asarray(goal, dtype=np.float64)))):
        program.appendMoveInstruction(cl.MoveInstructionPoly_wrap_MoveInstruction(
            cl.MoveInstruction(wp, cl.MoveInstructionType_FREESPACE, cl.DEFAULT_PROFILE_KEY)))
    task = factory.createTaskComposerNode(pipeline)
    data = tcomp.TaskComposerDataStorage()
    data.setData(task.getInputKeys().get("program"), cl.AnyPoly_wrap_CompositeInstruction(program))
    data.setData("environment", te.AnyPoly_wrap_EnvironmentConst(env))
    data.setData("profiles", cl.AnyPoly_wrap_ProfileDictionary(cl.ProfileDictionary()))
    executor = factory.createTaskComposerExecutor("TaskflowExecutor")
    begin = time.perf_counter()
    future = executor.run(task.get(), data)
    future.wait()
    seconds = time.perf_counter() - begin
    if not future.context.isSuccessful():
        return {"success": False, "seconds": seconds, "path": None}
    result = cl.AnyPoly_as_CompositeInstruction(
        future.context.data_storage.getData(task.getOutputKeys().get("program")))
    path, kinds = [], []
    for instruction in result:
        move = cl.InstructionPoly_as_MoveInstructionPoly(instruction)  # keep proxies alive
        waypoint = move.getWaypoint()
        kinds.append("state" if waypoint.isStateWaypoint() else
                     "joint" if waypoint.isJointWaypoint() else "other")
        if kinds[-1] == "other":
            continue
        state = (cl.WaypointPoly_as_StateWaypointPoly(waypoint) if kinds[-1] == "state"
                 else cl.WaypointPoly_as_JointWaypointPoly(waypoint))
        path.append(np.asarray(state.getPosition()).flatten().tolist())
    return {"success": True, "seconds": seconds, "path": path, "waypoint_kinds": kinds}


def plans(problems: list, items: list, root: str, pipeline: str) -> list:
    env = load()
    add_scene(env, items, root)
    names = list(env.getKinematicGroup(GROUP).getJointNames())
    factory = tcomp.TaskComposerPluginFactory(
        common.FilesystemPath(str(FOLDER / "task_composer_plugins.yaml")),
        common.GeneralResourceLocator())
    return [plan(env, factory, pipeline, names, p["start"], p["goal"], root) for p in problems]


def main() -> None:
    root = request["root"]
    env = load()
    out = {"description": describe(env)}
    if "fk" in request:
        out["fk"] = fk(env, request["fk"])
    if "ik" in request:
        out["ik"] = ik(env, request["ik"], root, request.get("ik_restarts", 0))
    if "collisions" in request:
        out["collisions"] = {
            name: collisions(case["q"], read_scene(case["scene_file"], request["classes"]), root)
            for name, case in request["collisions"].items()}
    if "plans" in request:
        case = request["plans"]
        out["plans"] = plans(case["problems"],
                             read_scene(case["scene_file"], request["classes"]), root,
                             case["pipeline"])
    Path(sys.argv[2]).write_text(json.dumps(out))


main()
