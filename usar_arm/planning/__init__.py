"""Planning on a described arm: :class:`Robot` (a description with its solvers), kinematics
(Pinocchio), inverse kinematics (closed form and Newton polish compiled, LM for other arms),
collision worlds (compiled verdicts, python-fcl for the undecided; docs/architecture.md),
scenes, PTP plans through OMPL and straight-line LIN paths."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.planning.collision import CollisionWorld, Contact
    from usar_arm.planning.compiled import warm_up
    from usar_arm.planning.ik import BatchIKResult, IKOptions, IKResult, IKSolution, IKSolver
    from usar_arm.planning.kinematics import KinematicModel
    from usar_arm.planning.lin import LinOptions, LinPath, plan_lin
    from usar_arm.planning.ompl_adapter import OmplOptions
    from usar_arm.planning.ptp import PtpPlan, plan_to_joints, plan_to_pose
    from usar_arm.planning.robot import Robot, robot_from_files, robot_from_texts
    from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, SceneObject, Sphere
    from usar_arm.planning.scene_file import load_scene, parse_scene

_HOMES = {
    "collision": ("CollisionWorld", "Contact"),
    "compiled": ("warm_up",),
    "ik": ("BatchIKResult", "IKOptions", "IKResult", "IKSolution", "IKSolver"),
    "kinematics": ("KinematicModel",),
    "lin": ("LinOptions", "LinPath", "plan_lin"),
    "ompl_adapter": ("OmplOptions",),
    "ptp": ("PtpPlan", "plan_to_joints", "plan_to_pose"),
    "robot": ("Robot", "robot_from_files", "robot_from_texts"),
    "scene": ("Box", "CylinderShape", "Mesh", "Scene", "SceneObject", "Sphere"),
    "scene_file": ("load_scene", "parse_scene"),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["BatchIKResult", "Box", "CollisionWorld", "Contact", "CylinderShape", "IKOptions",
           "IKResult", "IKSolution", "IKSolver", "KinematicModel", "LinOptions", "LinPath", "Mesh",
           "OmplOptions", "PtpPlan", "Robot", "Scene", "SceneObject", "Sphere", "load_scene",
           "parse_scene", "plan_lin", "plan_to_joints", "plan_to_pose", "robot_from_files",
           "robot_from_texts", "warm_up"]

__getattr__ = exports(__name__, _HOMES)
