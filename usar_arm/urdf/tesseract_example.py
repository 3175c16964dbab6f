"""The Python example a Tesseract config folder carries (``plan_example.py``, also quoted in its
README): load the folder, plan a free-space motion through the task composer, print it.

It imports only ``tesseract_robotics`` and numpy, so it runs in a venv with nothing but
``pip install tesseract-robotics==0.5.1``.
"""

from __future__ import annotations

from collections.abc import Sequence

from usar_arm.urdf.writer import num

TEMPLATE = '''"""Plan with Tesseract on the {robot} described by usar-arm.

    python plan_example.py [PIPELINE]   # OMPLPipeline (default), TrajOptPipeline or
                                        # FreespacePipeline; needs tesseract-robotics 0.5.1
"""
import os
import sys
from pathlib import Path

import numpy as np

FOLDER = Path(__file__).resolve().parent
# package:// URLs in the SRDF name this folder: Tesseract finds it through this variable.
os.environ["TESSERACT_RESOURCE_PATH"] = str(FOLDER)

from tesseract_robotics.tesseract_command_language import (  # noqa: E402
    DEFAULT_PROFILE_KEY, AnyPoly_as_CompositeInstruction, AnyPoly_wrap_CompositeInstruction,
    AnyPoly_wrap_ProfileDictionary, CompositeInstruction, CompositeInstructionOrder_ORDERED,
    InstructionPoly_as_MoveInstructionPoly, JointWaypoint, JointWaypointPoly_wrap_JointWaypoint,
    MoveInstruction, MoveInstructionPoly_wrap_MoveInstruction, MoveInstructionType_FREESPACE,
    ProfileDictionary, StateWaypoint, StateWaypointPoly_wrap_StateWaypoint,
    WaypointPoly_as_StateWaypointPoly)
from tesseract_robotics.tesseract_common import (  # noqa: E402
    FilesystemPath, GeneralResourceLocator, ManipulatorInfo)
from tesseract_robotics.tesseract_environment import (  # noqa: E402
    AnyPoly_wrap_EnvironmentConst, Environment)
from tesseract_robotics.tesseract_task_composer import (  # noqa: E402
    TaskComposerDataStorage, TaskComposerPluginFactory)

locator = GeneralResourceLocator()
env = Environment()
if not env.init(FilesystemPath(str(FOLDER / "{robot}.urdf")),
                FilesystemPath(str(FOLDER / "{robot}.srdf")), locator):
    sys.exit("Tesseract could not load the description")
group = env.getKinematicGroup("{group}")  # {solver} inverse kinematics
joints = list(group.getJointNames())
start = np.array([{start}], dtype=np.float64)  # rad (m for prismatic joints)
goal = np.array([{goal}], dtype=np.float64)

manip = ManipulatorInfo()
manip.manipulator, manip.working_frame, manip.tcp_frame = "{group}", "{base}", "{tip}"
program = CompositeInstruction(DEFAULT_PROFILE_KEY, manip, CompositeInstructionOrder_ORDERED)
for waypoint in (StateWaypointPoly_wrap_StateWaypoint(StateWaypoint(joints, start)),
                 JointWaypointPoly_wrap_JointWaypoint(JointWaypoint(joints, goal))):
    program.appendMoveInstruction(MoveInstructionPoly_wrap_MoveInstruction(
        MoveInstruction(waypoint, MoveInstructionType_FREESPACE, DEFAULT_PROFILE_KEY)))

factory = TaskComposerPluginFactory(FilesystemPath(str(FOLDER / "task_composer_plugins.yaml")),
                                    locator)
task = factory.createTaskComposerNode(sys.argv[1] if len(sys.argv) > 1 else "OMPLPipeline")
data = TaskComposerDataStorage()
data.setData(task.getInputKeys().get("program"), AnyPoly_wrap_CompositeInstruction(program))
data.setData("environment", AnyPoly_wrap_EnvironmentConst(env))
data.setData("profiles", AnyPoly_wrap_ProfileDictionary(ProfileDictionary()))  # defaults
executor = factory.createTaskComposerExecutor("TaskflowExecutor")
future = executor.run(task.get(), data)
future.wait()
if not future.context.isSuccessful():
    sys.exit("planning failed")
result = AnyPoly_as_CompositeInstruction(
    future.context.data_storage.getData(task.getOutputKeys().get("program")))
for instruction in result:
    move = InstructionPoly_as_MoveInstructionPoly(instruction)  # keep each SWIG proxy alive
    waypoint = move.getWaypoint()
    state = WaypointPoly_as_StateWaypointPoly(waypoint)
    print(f"t = {{state.getTime():7.3f}} s  q = {{np.round(state.getPosition().flatten(), 4)}}")
'''


def example_script(robot: str, group: str, base: str, tip: str, solver: str,
                   start: Sequence[float], goal: Sequence[float]) -> str:
    """``plan_example.py``: plan from ``start`` to ``goal`` (rad, m) with the task composer."""
    return TEMPLATE.format(robot=robot, group=group, base=base, tip=tip, solver=solver,
                           start=", ".join(num(v) for v in start),
                           goal=", ".join(num(v) for v in goal))
