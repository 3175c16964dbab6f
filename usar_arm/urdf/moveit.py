"""A complete MoveIt 2 config package as text files (docs/conventions.md section 3).

The package needs no separate description package: the URDF sits in ``config/`` and the
modified ``config/<robot>.urdf.xacro`` includes it and the ros2_control macro by relative path.
The planning files (``ompl_planning.yaml``, ``sensors_3d.yaml``, ``moveit.rviz``) come from
:mod:`.moveit_planning`.
"""

from __future__ import annotations

from collections.abc import Sequence

from usar_arm.core.model import KinematicChain
from usar_arm.core.version import __version__
from usar_arm.urdf import moveit_gripper as grip
from usar_arm.urdf.moveit_planning import DEFAULT_DISTRO, check_distro, planning_files
from usar_arm.urdf.srdf import GROUP
from usar_arm.urdf.writer import num

LAUNCHES = ("demo", "move_group", "moveit_rviz", "rsp", "setup_assistant",
            "spawn_controllers", "static_virtual_joint_tfs", "warehouse_db")


def package_name(robot: str) -> str:
    """``KR60`` -> ``kr60_moveit_config``."""
    return f"{robot.lower()}_moveit_config"


def _yaml_list(items: Sequence[str], indent: int) -> list[str]:
    return [" " * indent + f"- {item}" for item in items]


def moveit_files(chain: KinematicChain, urdf: str, srdf: str, joint_limits: str,
                 controller: str, home: dict[str, float], distro: str = DEFAULT_DISTRO,
                 gripper: bool = False) -> dict[str, str]:
    """Relative path -> text of every file of the package, for ROS 2 ``distro`` (``humble`` or
    ``jazzy``: ``ompl_planning.yaml``'s keys differ; the package records which); ``gripper``:
    with the vacuum's virtual joint and its GripperCommand controller
    (:mod:`.moveit_gripper`).

    Raises:
        InvalidInputError: ``gripper`` for an arm without a tool.
    """
    check_distro(distro)
    robot = chain.name
    joints = list(chain.joint_names)
    tool = chain if gripper else None
    if tool is not None:
        srdf = grip.with_gripper_srdf(srdf, tool)
        joint_limits = joint_limits.rstrip("\n") + "\n" + "\n".join(
            grip.joint_limits_lines(tool)) + "\n"
    files = {f"config/{robot}.urdf": urdf, f"config/{robot}.srdf": srdf,
             "config/joint_limits.yaml": joint_limits}
    files.update(_xacro_files(robot, joints, home, tool))
    files.update(_controller_files(joints, controller, tool))
    files.update(_package_files(robot, distro, tool is not None))
    files.update(planning_files(chain, distro))
    return files


def _xacro_files(robot: str, joints: list[str], home: dict[str, float],
                 tool: KinematicChain | None = None) -> dict[str, str]:
    """The robot's xacro (the URDF, the gripper's virtual joint when ``tool``, and the mock
    hardware's ros2_control macro) and the mock hardware's initial positions (``home``, rad
    or m per joint)."""
    files: dict[str, str] = {}
    files[f"config/{robot}.urdf.xacro"] = "\n".join([
        '<?xml version="1.0" encoding="utf-8"?>',
        f'<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="{robot}">',
        '  <xacro:arg name="initial_positions_file" default="initial_positions.yaml"/>',
        f'  <xacro:include filename="{robot}.urdf"/>',
        *(grip.xacro_lines(tool) if tool is not None else []),
        f'  <xacro:include filename="{robot}.ros2_control.xacro"/>',
        f'  <xacro:{robot}_ros2_control name="FakeSystem" '
        'initial_positions_file="$(arg initial_positions_file)"/>',
        "</robot>", ""])
    control = [
        '<?xml version="1.0" encoding="utf-8"?>',
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro">',
        f'  <xacro:macro name="{robot}_ros2_control" params="name initial_positions_file">',
        '    <xacro:property name="initial_positions" '
        "value=\"${xacro.load_yaml(initial_positions_file)['initial_positions']}\"/>",
        '    <ros2_control name="${name}" type="system">',
        "      <hardware>",
        "        <plugin>mock_components/GenericSystem</plugin>",
        "      </hardware>"]
    for j in joints:
        control += [
            f'      <joint name="{j}">',
            '        <command_interface name="position"/>',
            '        <state_interface name="position">',
            f"          <param name=\"initial_value\">${{initial_positions['{j}']}}</param>",
            "        </state_interface>",
            '        <state_interface name="velocity"/>',
            "      </joint>"]
    control += grip.control_lines(tool) if tool is not None else []
    control += ["    </ros2_control>", "  </xacro:macro>", "</robot>", ""]
    files[f"config/{robot}.ros2_control.xacro"] = "\n".join(control)
    files["config/initial_positions.yaml"] = "\n".join(
        ["# Default initial positions for the mock hardware (the SRDF's home state).",
         "initial_positions:"] + [f"  {j}: {num(home[j])}" for j in joints]) + "\n"
    return files


def _controller_files(joints: list[str], controller: str, tool: KinematicChain | None = None
                      ) -> dict[str, str]:
    """Kinematics, Pilz limits, and the ros2_control and MoveIt controllers (``controller``
    drives ``joints``; with ``tool``, the gripper's controller too)."""
    files: dict[str, str] = {}
    entry, block = grip.ros2_controller_lines(tool) if tool is not None else ([], [])
    names = [controller] + ([grip.gripper_of(tool)[0]] if tool is not None else [])
    files["config/kinematics.yaml"] = "\n".join([
        f"{GROUP}:",
        "  kinematics_solver: kdl_kinematics_plugin/KDLKinematicsPlugin",
        "  kinematics_solver_search_resolution: 0.005",
        "  kinematics_solver_timeout: 0.05", ""])
    files["config/pilz_cartesian_limits.yaml"] = "\n".join([
        "# Cartesian limits for the Pilz industrial motion planner (LIN/CIRC).",
        "cartesian_limits:",
        "  max_trans_vel: 1.0",
        "  max_trans_acc: 2.25",
        "  max_trans_dec: -5.0",
        "  max_rot_vel: 1.57", ""])
    files["config/ros2_controllers.yaml"] = "\n".join([
        "controller_manager:",
        "  ros__parameters:",
        "    update_rate: 100  # Hz",
        f"    {controller}:",
        "      type: joint_trajectory_controller/JointTrajectoryController",
        *entry,
        "    joint_state_broadcaster:",
        "      type: joint_state_broadcaster/JointStateBroadcaster",
        f"{controller}:",
        "  ros__parameters:",
        "    joints:", *_yaml_list(joints, 6),
        "    command_interfaces:", "      - position",
        "    state_interfaces:", "      - position", "      - velocity",
        "    allow_nonzero_velocity_at_trajectory_end: true", *block, ""])
    files["config/moveit_controllers.yaml"] = "\n".join([
        "moveit_controller_manager: moveit_simple_controller_manager/MoveItSimpleControllerManager",
        "moveit_simple_controller_manager:",
        "  controller_names:", *_yaml_list(names, 4),
        f"  {controller}:",
        "    type: FollowJointTrajectory",
        "    action_ns: follow_joint_trajectory",
        "    default: true",
        "    joints:", *_yaml_list(joints, 6),
        *(grip.moveit_controller_lines(tool) if tool is not None else []),
        "trajectory_execution:",
        "  allowed_execution_duration_scaling: 1.2",
        "  allowed_goal_duration_margin: 0.5",
        "  allowed_start_tolerance: 0.01", ""])
    return files


def _package_files(robot: str, distro: str, gripper: bool = False) -> dict[str, str]:
    """The package's own files: Setup Assistant record, package.xml, CMakeLists.txt and the
    launch files."""
    pkg = package_name(robot)
    files: dict[str, str] = {}
    files[".setup_assistant"] = "\n".join([
        f"# written by usar-arm for ROS 2 {distro} (usar-arm moveit-config --ros-distro "
        f"{distro})",
        "moveit_setup_assistant_config:",
        "  URDF:",
        f"    package: {pkg}",
        f"    relative_path: config/{robot}.urdf",
        "    xacro_args: \"\"",
        "  SRDF:",
        f"    relative_path: config/{robot}.srdf",
        "  package_settings:",
        "    author_name: usar-arm",
        "    author_email: usar-arm@example.invalid",
        "    generated_timestamp: 0  # written by usar-arm, not by the Setup Assistant",
        "  control_xacro:",
        "    command:", "      - position",
        "    state:", "      - position", "      - velocity", ""])
    files["package.xml"] = "\n".join([
        '<?xml version="1.0"?>',
        '<package format="3">',
        f"  <name>{pkg}</name>",
        "  <version>0.1.0</version>",
        f"  <description>MoveIt 2 configuration of the USARSim {robot} for ROS 2 "
        f"{distro.capitalize()}, generated by usar-arm {__version__} from what the simulator "
        "described over its TCP protocol.</description>",
        '  <maintainer email="usar-arm@example.invalid">usar-arm</maintainer>',
        "  <license>Apache-2.0</license>",
        "  <buildtool_depend>ament_cmake</buildtool_depend>",
        *[f"  <exec_depend>{d}</exec_depend>" for d in (
            "moveit_ros_move_group", "moveit_kinematics", "moveit_planners",
            "moveit_simple_controller_manager", "moveit_configs_utils", "moveit_ros_visualization",
            "moveit_setup_assistant", "joint_state_publisher", "joint_state_publisher_gui",
            "robot_state_publisher", "tf2_ros", "xacro", "controller_manager",
            "joint_trajectory_controller", "joint_state_broadcaster", "rviz2",
            "warehouse_ros_mongo", *(["gripper_controllers"] if gripper else []))],
        "  <export>", "    <build_type>ament_cmake</build_type>", "  </export>",
        "</package>", ""])
    files["CMakeLists.txt"] = "\n".join([
        "cmake_minimum_required(VERSION 3.22)",
        f"project({pkg})",
        "find_package(ament_cmake REQUIRED)",
        "ament_package()",
        "install(DIRECTORY launch DESTINATION share/${PROJECT_NAME}",
        '  PATTERN "setup_assistant.launch" EXCLUDE)',
        "install(DIRECTORY config DESTINATION share/${PROJECT_NAME})",
        "install(FILES .setup_assistant DESTINATION share/${PROJECT_NAME})", ""])
    for name in LAUNCHES:
        files[f"launch/{name}.launch.py"] = "\n".join([
            "from moveit_configs_utils import MoveItConfigsBuilder",
            f"from moveit_configs_utils.launches import generate_{name}_launch",
            "", "",
            "def generate_launch_description():",
            f'    moveit_config = MoveItConfigsBuilder("{robot}", package_name="{pkg}")'
            ".to_moveit_configs()",
            f"    return generate_{name}_launch(moveit_config)", ""])
    return files
