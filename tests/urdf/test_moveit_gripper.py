"""`usar-arm moveit-config --gripper`: the vacuum as MoveIt drives a gripper, a virtual joint
KR60gripper_suction (0 off, 1 on) declared in the package's xacro and SRDF only, moved by a
GripperCommand controller whose action is the node's KR60gripper/gripper_cmd; the robot's own
URDF is untouched, and an arm without a tool is refused."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from usar_arm.core.errors import InvalidInputError
from usar_arm.planning.robot import robot_from_files
from usar_arm.urdf.moveit import moveit_files

GENERATED = Path(__file__).resolve().parents[2] / "robots" / "generated"
JOINT = "KR60gripper_suction"


def _files(gripper: bool) -> dict[str, str]:
    robot = robot_from_files(GENERATED / "KR60.urdf")
    chain = robot.chain
    return moveit_files(chain, (GENERATED / "KR60.urdf").read_text(),
                        (GENERATED / "KR60.srdf").read_text(),
                        (GENERATED / "KR60.joint_limits.yaml").read_text(),
                        "KR60Arm_controller", dict.fromkeys(chain.joint_names, 0.0),
                        gripper=gripper)


def test_the_gripper_controller_drives_the_nodes_action_through_a_virtual_joint() -> None:
    files = _files(gripper=True)
    moveit = yaml.safe_load(files["config/moveit_controllers.yaml"])
    manager = moveit["moveit_simple_controller_manager"]
    assert manager["controller_names"] == ["KR60Arm_controller", "KR60gripper"]
    assert manager["KR60gripper"] == {"type": "GripperCommand", "action_ns": "gripper_cmd",
                                      "default": True, "joints": [JOINT]}
    ros2 = yaml.safe_load(files["config/ros2_controllers.yaml"])
    assert ros2["controller_manager"]["ros__parameters"]["KR60gripper"]["type"] == \
        "position_controllers/GripperActionController"
    assert ros2["KR60gripper"]["ros__parameters"]["joint"] == JOINT
    assert ros2["KR60Arm_controller"]["ros__parameters"]["joints"][0] == "joint_a1"
    limits = yaml.safe_load(files["config/joint_limits.yaml"])["joint_limits"]
    assert (limits[JOINT]["min_position"], limits[JOINT]["max_position"]) == (0, 1)
    srdf = files["config/KR60.srdf"]
    group = re.search(r'<group name="gripper">(.*?)</group>', srdf, re.S)
    assert group is not None and f'<joint name="{JOINT}"/>' in group.group(1)
    for state, value in (("open", 0), ("closed", 1)):
        assert re.search(rf'<group_state name="{state}" group="gripper">\s*<joint name="{JOINT}" '
                         rf'value="{value}"/>', srdf)
    assert JOINT not in files["config/KR60.urdf"]  # the robot's own URDF is untouched
    assert "<exec_depend>gripper_controllers</exec_depend>" in files["package.xml"]


def test_the_package_xacro_expands_with_the_suction_joint(tmp_path: Path) -> None:
    for rel, text in _files(gripper=True).items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    exe = shutil.which("xacro") or str(Path(sys.executable).parent / "xacro")
    run = subprocess.run([exe, str(tmp_path / "config" / "KR60.urdf.xacro")],
                         capture_output=True, text=True, check=False, cwd="/")
    assert run.returncode == 0, run.stderr
    assert re.search(rf'<joint name="{JOINT}" type="prismatic">\s*<parent link="KR60gripper_tcp"'
                     rf'/>\s*<child link="{JOINT}_link"/>', run.stdout)
    control = run.stdout[run.stdout.index("<ros2_control"):]
    assert re.findall(r'<joint name="([^"]+)">', control) == [
        *(f"joint_a{i}" for i in range(1, 7)), JOINT]


def test_without_the_option_the_package_has_no_gripper() -> None:
    files = _files(gripper=False)
    assert all(JOINT not in text for text in files.values())
    assert "KR60gripper:" not in files["config/moveit_controllers.yaml"]


def test_an_arm_without_a_tool_is_refused() -> None:
    robot = robot_from_files(GENERATED / "KR60.urdf")
    chain = robot.chain
    bare = type(chain)(**{**chain.__dict__, "frames": {k: v for k, v in chain.frames.items()
                                                       if k not in ("tool", "tcp")}})
    with pytest.raises(InvalidInputError, match="no tool"):
        moveit_files(bare, "", (GENERATED / "KR60.srdf").read_text(), "", "c",
                     dict.fromkeys(chain.joint_names, 0.0), gripper=True)
