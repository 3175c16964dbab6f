"""Motion planning with Tesseract 0.28 (tesseract-robotics 0.5.1) through its task composer:
python run_tesseract_plan.py [--pipeline OMPLPipeline|TrajOptPipeline] PROBLEMS.json RESULTS.json

Environment from the problem's "tesseract" folder (ts_scene.load), obstacles per scene
(ts_scene.Obstacles). Each problem is a program of two FREESPACE moves (start state, joint
goal) run through the folder's task_composer_plugins.yaml pipeline (one Taskflow thread) with
an empty ProfileDictionary, i.e. Tesseract's default profiles:

* OMPLPipeline: min length -> OMPL (default profile: parallel RRTConnect, 5 s planning time;
  the profile's solver settings are not bound in Python 0.5.1, so the benchmark's 2 s budget
  cannot be given: answers after 2 s are not verified) -> discrete contact check -> iterative
  spline;
* TrajOptPipeline: the same with TrajOpt (a local optimiser seeded with the straight joint
  line: it applies where a path near that line exists) instead of OMPL.

Timed ("seconds"): the whole pipeline run (executor.run + wait), so it includes the contact
check and the time parameterisation. "path": the output waypoints; "duration_s": the time of
the last one (iterative spline, the URDF's velocity limits).
"""

import sys
import time

import numpy as np

pipeline = "OMPLPipeline"
if len(sys.argv) > 2 and sys.argv[1] == "--pipeline":
    pipeline = sys.argv[2]
    del sys.argv[1:3]

import peerio  # noqa: E402
import ts_scene  # noqa: E402
from tesseract_robotics import tesseract_command_language as cl  # noqa: E402
from tesseract_robotics import tesseract_common as common  # noqa: E402
from tesseract_robotics import tesseract_environment as te  # noqa: E402
from tesseract_robotics import tesseract_task_composer as tcomp  # noqa: E402

spec, out = peerio.args()
names = spec["joint_names"]
env, group_names = ts_scene.load(spec)
obstacles = ts_scene.Obstacles(env, spec["scenes"])
factory = tcomp.TaskComposerPluginFactory(
    common.FilesystemPath(str(ts_scene.Path(spec["tesseract"]) / "task_composer_plugins.yaml")),
    common.GeneralResourceLocator())
executor = factory.createTaskComposerExecutor("TaskflowExecutor")
manip = common.ManipulatorInfo()
manip.manipulator = spec.get("group", "manipulator")
manip.working_frame = spec.get("base_link", "base_link")
manip.tcp_frame = spec.get("tip_link", "tool0")


def program(start, goal):
    prog = cl.CompositeInstruction(cl.DEFAULT_PROFILE_KEY, manip,
                                   cl.CompositeInstructionOrder_ORDERED)
    for wp in (cl.StateWaypointPoly_wrap_StateWaypoint(cl.StateWaypoint(group_names, start)),
               cl.JointWaypointPoly_wrap_JointWaypoint(cl.JointWaypoint(group_names, goal))):
        prog.appendMoveInstruction(cl.MoveInstructionPoly_wrap_MoveInstruction(
            cl.MoveInstruction(wp, cl.MoveInstructionType_FREESPACE, cl.DEFAULT_PROFILE_KEY)))
    return prog


def solve(p):
    start = np.array(peerio.reorder(p["start"], names, group_names), dtype=np.float64)
    goal = np.array(peerio.reorder(p["goal"], names, group_names), dtype=np.float64)
    task = factory.createTaskComposerNode(pipeline)
    data = tcomp.TaskComposerDataStorage()
    data.setData(task.getInputKeys().get("program"),
                 cl.AnyPoly_wrap_CompositeInstruction(program(start, goal)))
    data.setData("environment", te.AnyPoly_wrap_EnvironmentConst(env))
    data.setData("profiles", cl.AnyPoly_wrap_ProfileDictionary(cl.ProfileDictionary()))
    begin = time.perf_counter()
    future = executor.run(task.get(), data)
    future.wait()
    seconds = time.perf_counter() - begin
    if not future.context.isSuccessful():
        return {"success": False, "seconds": seconds, "path": None,
                "status": f"{pipeline} aborted"}
    result = cl.AnyPoly_as_CompositeInstruction(
        future.context.data_storage.getData(task.getOutputKeys().get("program")))
    path, times = [], []
    for instruction in result:
        move = cl.InstructionPoly_as_MoveInstructionPoly(instruction)  # keep proxies alive
        waypoint = move.getWaypoint()
        if not waypoint.isStateWaypoint():
            return {"success": False, "seconds": seconds, "path": None,
                    "status": "output holds unplanned waypoints"}
        state = cl.WaypointPoly_as_StateWaypointPoly(waypoint)
        path.append(peerio.reorder(np.asarray(state.getPosition()).flatten(), group_names,
                                   names))
        times.append(float(state.getTime()))
    return {"success": True, "seconds": seconds, "path": path, "duration_s": times[-1]}


peerio.write(
    out,
    peer="tesseract" if pipeline == "OMPLPipeline" else f"tesseract {pipeline}",
    dist="tesseract-robotics",
    stage="plan",
    results=peerio.solve_by_scene(spec["problems"], obstacles.enter, solve),
    settings={"pipeline": pipeline, "profiles": "Tesseract defaults (empty ProfileDictionary)",
              "executor": "TaskflowExecutor, 1 thread", "folder": spec["tesseract"]},
    notes=f"seconds = the whole {pipeline} (planner, contact check, iterative spline)",
)
