"""The MoveIt package's planning files, read the way their consumers read them: every YAML loads,
the OMPL pipeline names only planners MoveIt registers and the installed OMPL has, in the order
usar-arm's benchmark ranked them (bench/results/planners.json), with the pipeline keys and types
of the ROS 2 distribution it is written for; the segment fraction gives usar-arm's own edge
resolution, and the SRDF's disabled pairs are those usar-arm's planner skips."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
import yaml
from ompl import geometric as og

from usar_arm.core.errors import InvalidInputError
from usar_arm.description.cache import robot_from_description
from usar_arm.description.embedded import describe
from usar_arm.description.pipeline import DescribeOptions, Description
from usar_arm.planning.ompl_adapter import PROJECTED
from usar_arm.urdf.moveit import moveit_files
from usar_arm.urdf.moveit_planning import (
    CANDIDATES,
    PLANNERS,
    RANKED_ON,
    RANKING,
    ROS_DISTROS,
    ompl_planning_yaml,
)
from usar_arm.urdf.srdf import GROUP

RESULTS = Path(__file__).resolve().parents[2] / "bench" / "results" / "planners.json"
MOVEIT_PLANNERS = {
    "AnytimePathShortening", "BFMT", "BiEST", "BiTRRT", "BKPIECE", "EST", "FMT", "KPIECE",
    "LazyPRM", "LazyPRMstar", "LazyRRT", "LBKPIECE", "LBTRRT", "PDST", "PRM", "PRMstar",
    "ProjEST", "RRT", "RRTConnect", "RRTstar", "SBL", "SPARS", "SPARStwo", "STRIDE", "TRRT"}
"""The ``geometric::`` types MoveIt 2's OMPL interface registers
(``PlanningContextManager::registerDefaultPlanners``); any other type is refused at run time."""


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


def test_ompl_planning_names_only_planners_moveit_registers_and_ompl_has(package: tuple
                                                                        ) -> None:
    _, files = package
    doc = yaml.safe_load(files["config/ompl_planning.yaml"])
    types = [cfg["type"] for cfg in doc["planner_configs"].values()]
    assert types and all(t.startswith("geometric::") for t in types)
    names = [t.removeprefix("geometric::") for t in types]
    assert set(names) <= MOVEIT_PLANNERS, set(names) - MOVEIT_PLANNERS
    assert names == list(PLANNERS) and set(names) == set(CANDIDATES)
    for name in names:  # usar-arm's benchmark runs each one through the ompl wheel
        assert hasattr(og, CANDIDATES[name]), f"OMPL has no planner {CANDIDATES[name]}"
    group = doc[GROUP]
    assert group["default_planner_config"] == f"{PLANNERS[0]}kConfigDefault"
    assert group["planner_configs"] == list(doc["planner_configs"])


def test_the_planners_are_offered_in_the_order_the_benchmark_ranked_them() -> None:
    """moveit_planning.RANKING is bench/results/planners.json's ranking (planner, verified
    success, median time to the 3 digits the YAML's comments print), so the two cannot drift
    apart; the YAML's comments cite those figures."""
    doc = json.loads(RESULTS.read_text())
    measured = [(r["planner"], r["success_rate"], r["median_s"]) for r in doc["ranking"]]
    assert [m[0] for m in measured] == list(PLANNERS)
    for (name, success, median), (_, got_success, got_median) in zip(RANKING, measured,
                                                                     strict=True):
        assert success == pytest.approx(got_success, abs=1e-9), name
        assert float(f"{got_median:.3g}") == median, name
    count = doc["cases"]["KR60"]["problems"]["count"]
    assert RANKED_ON.startswith(f"{count} KR60 ") and str(count) in doc["settings"]["problems"]
    assert doc["ranking"][0]["success_rate"] == 1.0  # the default solves every problem


def test_every_planner_that_grids_a_projection_gets_the_yaml_s_from_usar_arm() -> None:
    gridded = {c for c in CANDIDATES.values() if hasattr(getattr(og, c),
                                                         "getProjectionEvaluator")}
    assert gridded == set(PROJECTED)


@pytest.mark.parametrize("distro", ROS_DISTROS)
def test_the_pipeline_has_the_keys_and_types_its_ros_distro_reads(package: tuple,
                                                                 distro: str) -> None:
    desc, _ = package
    doc = yaml.safe_load(ompl_planning_yaml(desc.chain, distro))
    if distro == "humble":  # strings; time parameterisation is a request adapter
        assert doc["planning_plugin"] == "ompl_interface/OMPLPlanner"
        assert isinstance(doc["request_adapters"], str)
        adapters = doc["request_adapters"].split()
        assert adapters[0] == "default_planner_request_adapters/AddTimeOptimalParameterization"
        assert all(a.startswith("default_planner_request_adapters/") for a in adapters)
        assert "planning_plugins" not in doc and "response_adapters" not in doc
    else:  # lists (a string stops move_group); time parameterisation answers
        assert doc["planning_plugins"] == ["ompl_interface/OMPLPlanner"]
        assert all(a.startswith("default_planning_request_adapters/")
                   for a in doc["request_adapters"])
        assert doc["response_adapters"][0] == \
            "default_planning_response_adapters/AddTimeOptimalParameterization"
        assert "planning_plugin" not in doc
    assert doc["start_state_max_bounds_error"] == 0.1


@pytest.mark.parametrize("distro", ROS_DISTROS)
def test_the_package_records_its_ros_distro(package: tuple, distro: str) -> None:
    desc, _ = package
    files = moveit_files(desc.chain, desc.urdf, desc.srdf, desc.joint_limits,
                         "KR60Arm_controller", desc.home, distro)
    assert f"--ros-distro {distro}" in files[".setup_assistant"]
    assert f"for ROS 2 {distro.capitalize()}" in files["package.xml"]
    assert yaml.safe_load(files[".setup_assistant"])["moveit_setup_assistant_config"]


def test_an_unknown_ros_distro_is_refused(package: tuple) -> None:
    desc, _ = package
    with pytest.raises(InvalidInputError, match="humble or jazzy"):
        ompl_planning_yaml(desc.chain, "iron")


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
