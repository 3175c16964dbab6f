"""The MoveIt package's planning files, read the way their consumers read them: every YAML loads,
the OMPL pipeline names only planners the installed OMPL has, the segment fraction gives usar-arm's
own edge resolution, and the SRDF's disabled pairs are those usar-arm's planner skips."""

from __future__ import annotations

import re

import pytest
import yaml
from ompl import geometric as og

from usar_arm.description import DescribeOptions, Description
from usar_arm.embedded import describe
from usar_arm.robot import robot_from_description
from usar_arm.urdf.moveit import moveit_files
from usar_arm.urdf.srdf import GROUP


@pytest.fixture(scope="module")
def package() -> tuple[Description, dict[str, str]]:
    desc = describe(DescribeOptions(accuracy_samples=0))
    return desc, moveit_files(desc.chain, desc.urdf, desc.srdf, desc.joint_limits,
                              "KR60Arm_controller", desc.home)


def test_the_setup_assistant_s_whole_file_list_is_written(package: tuple) -> None:
    _, files = package
    assert {"config/ompl_planning.yaml", "config/sensors_3d.yaml", "config/moveit.rviz"} <= set(
        files)
    for name, text in files.items():
        if name.endswith((".yaml", ".rviz", ".setup_assistant")):
            assert yaml.safe_load(text) is not None or name.endswith("sensors_3d.yaml"), name
    assert yaml.safe_load(files["config/sensors_3d.yaml"]) == {"sensors": []}


def test_ompl_planning_names_only_planners_ompl_has(package: tuple) -> None:
    _, files = package
    doc = yaml.safe_load(files["config/ompl_planning.yaml"])
    types = [cfg["type"] for cfg in doc["planner_configs"].values()]
    assert types and all(t.startswith("geometric::") for t in types)
    for t in types:
        assert hasattr(og, t.removeprefix("geometric::")), f"OMPL has no planner {t}"
    group = doc[GROUP]
    assert group["default_planner_config"] == "RRTConnectkConfigDefault"
    assert set(group["planner_configs"]) == set(doc["planner_configs"])
    assert doc["planning_plugins"] == ["ompl_interface/OMPLPlanner"]


def test_the_segment_fraction_gives_usar_arm_s_edge_resolution(package: tuple) -> None:
    desc, files = package
    group = yaml.safe_load(files["config/ompl_planning.yaml"])[GROUP]
    ranges = [j.limits.upper - j.limits.lower for j in desc.chain.actuated_joints]
    # MoveIt: a segment is the sum of the joints' changes, the extent the sum of their ranges.
    assert group["longest_valid_segment_fraction"] * sum(ranges) == pytest.approx(0.01, rel=1e-5)
    joints = re.fullmatch(r"joints\((.+)\)", group["projection_evaluator"])
    assert joints and set(joints.group(1).split(",")) <= set(desc.chain.joint_names)


def test_the_srdf_disables_exactly_the_pairs_usar_arm_s_planner_skips(package: tuple) -> None:
    desc, files = package
    srdf = files["config/KR60.srdf"]
    disabled = {frozenset(p) for p in re.findall(
        r'<disable_collisions link1="([^"]+)" link2="([^"]+)"', srdf)}
    world = robot_from_description(desc).collision_world()
    links = set(world.link_names)
    every = {frozenset((a, b)) for a in links for b in links if a < b}
    checked = {frozenset(p) for p in world.checked_pairs()}
    assert checked == {p for p in every - disabled}


def test_the_rviz_layout_opens_the_motion_planning_display(package: tuple) -> None:
    _, files = package
    doc = yaml.safe_load(files["config/moveit.rviz"])
    classes = [d["Class"] for d in doc["Visualization Manager"]["Displays"]]
    assert "moveit_rviz_plugin/MotionPlanning" in classes
    assert doc["Visualization Manager"]["Global Options"]["Fixed Frame"] == "base_link"


def test_the_package_holds_exactly_the_file_list_the_readme_gives(package: tuple) -> None:
    _, files = package
    config = {"KR60.urdf", "KR60.srdf", "KR60.urdf.xacro", "KR60.ros2_control.xacro",
              "initial_positions.yaml", "kinematics.yaml", "joint_limits.yaml",
              "pilz_cartesian_limits.yaml", "moveit_controllers.yaml", "ros2_controllers.yaml",
              "ompl_planning.yaml", "sensors_3d.yaml", "moveit.rviz"}
    launches = {"demo", "move_group", "moveit_rviz", "rsp", "setup_assistant",
                "spawn_controllers", "static_virtual_joint_tfs", "warehouse_db"}
    assert set(files) == ({"package.xml", "CMakeLists.txt", ".setup_assistant"}
                          | {f"config/{c}" for c in config}
                          | {f"launch/{n}.launch.py" for n in launches})
