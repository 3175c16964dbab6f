"""The live ROS interface (``usar-arm ros``, ``usar-arm ros --ros1``, docs/ros.md).

* :mod:`.build`: builds the ROS 2 message packages the package index lacks (no rclpy);
  :mod:`.ros1_setup` makes the ROS 1 environment (no rospy), :mod:`.ros1_build` generates
  control_msgs there with genpy;
* :mod:`.goals`, :mod:`.frames`, :mod:`.runner`: the driver's rules as plain Python (goal
  checks, the transform tree, running goals on usar-arm's executor); :mod:`.drive` and
  :mod:`.platform_state` those of a ground vehicle (cmd_vel to wheel speeds, odometry, scans);
* :mod:`.node` (an arm) and :mod:`.platform_node` (a ground vehicle): the nodes' logic, for
  both middlewares, through :mod:`.transport`'s records and protocol; :mod:`.convert` turns the
  records into messages;
* :mod:`.ros2` and :mod:`.ros1`: the transports, the only modules that import rclpy and rospy
  (and their message packages).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.ros.build import BuiltInterfaces, RosSetupError, setup
    from usar_arm.ros.frames import TransformTree
    from usar_arm.ros.goals import CheckedGoal, GoalRejected, TrajectoryGoal, check_goal
    from usar_arm.ros.runner import GoalRunner

_HOMES = {
    "build": ("BuiltInterfaces", "RosSetupError", "setup"),
    "frames": ("TransformTree",),
    "goals": ("CheckedGoal", "GoalRejected", "TrajectoryGoal", "check_goal"),
    "runner": ("GoalRunner",),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy). The node itself
(:mod:`.node`, :mod:`.platform_node`) is run by ``usar-arm ros``; none of these names imports
rclpy."""

__all__ = ["BuiltInterfaces", "CheckedGoal", "GoalRejected", "GoalRunner", "RosSetupError",
           "TrajectoryGoal", "TransformTree", "check_goal", "setup"]

__getattr__ = exports(__name__, _HOMES)
