"""The vacuum gripper in a MoveIt 2 config package (``usar-arm moveit-config --gripper``).

MoveIt drives a gripper through a joint: its ``gripper`` group's joint, moved by a
``GripperCommand`` controller (moveit_simple_controller_manager), which sends the joint's
target as ``command.position`` to ``<controller>/gripper_cmd``. A vacuum has no such joint, so
the package declares a virtual one, ``<gripper>_suction`` (prismatic, 0 = vacuum off / open,
1 = on / closed, no geometry), from the tool's TCP, in **its own xacro only**: the robot's URDF
(``config/<robot>.urdf``, what ``usar-arm urdf`` writes and the node publishes) stays as it is.
The controller is named after the gripper, so its action is the node's
``<gripper>/gripper_cmd``; the mock hardware runs ros2_controllers' GripperActionController
under the same name. MoveIt's state monitor needs the joint's state: run the node with
``gripper_joint_states`` (docs/ros.md, the effectors' section).
"""

from __future__ import annotations

import re

from usar_arm.core.errors import InvalidInputError
from usar_arm.core.model import KinematicChain
from usar_arm.urdf.srdf import GRIPPER_GROUP

SUFFIX = "_suction"
"""The virtual joint's name after the gripper's (the node's ``SUCTION_SUFFIX``)."""
ACTION_NS = "gripper_cmd"
"""The GripperCommand action under the controller's name (gripper_action_controller's)."""


def gripper_of(chain: KinematicChain) -> tuple[str, str]:
    """(the gripper's name, the link its virtual joint hangs from: its TCP, else the tool).

    Raises:
        InvalidInputError: the arm has no tool (nothing to write a gripper controller for).
    """
    tool = chain.frames.get("tool")
    if tool is None:
        raise InvalidInputError(f"{chain.name} has no tool in its description (no effector was "
                         "learnt): there is no gripper to write a controller for")
    return tool, chain.frames.get("tcp", tool)


def suction_joint(chain: KinematicChain) -> str:
    """The virtual joint's name, ``<gripper>_suction``."""
    return gripper_of(chain)[0] + SUFFIX


def xacro_lines(chain: KinematicChain) -> list[str]:
    """The virtual joint and its empty link, for the package's robot xacro."""
    _, parent = gripper_of(chain)
    joint = suction_joint(chain)
    return ["  <!-- The vacuum as MoveIt drives it: 0 off (open), 1 on (closed). -->",
            f'  <link name="{joint}_link"/>',
            f'  <joint name="{joint}" type="prismatic">',
            f'    <parent link="{parent}"/>',
            f'    <child link="{joint}_link"/>',
            '    <axis xyz="0 0 1"/>',
            '    <limit lower="0" upper="1" effort="1" velocity="10"/>',
            "  </joint>"]


def control_lines(chain: KinematicChain) -> list[str]:
    """The virtual joint in the mock hardware's ros2_control macro (starts at 0, off)."""
    return [f'      <joint name="{suction_joint(chain)}">',
            '        <command_interface name="position"/>',
            '        <state_interface name="position">',
            '          <param name="initial_value">0</param>',
            "        </state_interface>",
            '        <state_interface name="velocity"/>',
            "      </joint>"]


def ros2_controller_lines(chain: KinematicChain) -> tuple[list[str], list[str]]:
    """(the controller's entry under controller_manager, its parameters block)."""
    name = gripper_of(chain)[0]
    return ([f"    {name}:", "      type: position_controllers/GripperActionController"],
            [f"{name}:", "  ros__parameters:", f"    joint: {suction_joint(chain)}"])


def moveit_controller_lines(chain: KinematicChain) -> list[str]:
    """The GripperCommand controller of moveit_simple_controller_manager."""
    return [f"  {gripper_of(chain)[0]}:",
            "    type: GripperCommand",
            f"    action_ns: {ACTION_NS}",
            "    default: true",
            "    joints:", f"      - {suction_joint(chain)}"]


def joint_limits_lines(chain: KinematicChain) -> list[str]:
    """The virtual joint's entry under ``joint_limits:`` (0 to 1, switched at once)."""
    return [f"  {suction_joint(chain)}:", "    has_position_limits: true",
            "    min_position: 0", "    max_position: 1", "    has_velocity_limits: true",
            "    max_velocity: 10", "    has_acceleration_limits: true",
            "    max_acceleration: 100"]


def with_gripper_srdf(srdf: str, chain: KinematicChain) -> str:
    """The SRDF with the virtual joint in the gripper group and its ``open`` and ``closed``
    states.

    Raises:
        InvalidInputError: the SRDF has no gripper group.
    """
    group = re.search(rf'  <group name="{GRIPPER_GROUP}">\n(.*?)  </group>\n', srdf, re.S)
    if group is None:
        raise InvalidInputError(f"the SRDF has no {GRIPPER_GROUP!r} group to add the suction "
                                "joint to")
    joint = suction_joint(chain)
    states = "".join(f'  <group_state name="{name}" group="{GRIPPER_GROUP}">\n'
                     f'    <joint name="{joint}" value="{value}"/>\n  </group_state>\n'
                     for name, value in (("open", 0), ("closed", 1)))
    block = (f'  <group name="{GRIPPER_GROUP}">\n{group.group(1)}    <joint name="{joint}"/>\n'
             f"  </group>\n{states}")
    return srdf[:group.start()] + block + srdf[group.end():]
