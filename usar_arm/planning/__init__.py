"""Planning on a described arm: :class:`Robot` (a description with its solvers), kinematics
(Pinocchio), inverse kinematics (closed form and Newton polish compiled, LM for other arms),
collision worlds (compiled verdicts, python-fcl for the undecided; docs/architecture.md),
scenes, PTP plans through OMPL and straight-line LIN paths."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.planning.attached import AttachedBody as AttachedBody
    from usar_arm.planning.collision import CollisionWorld as CollisionWorld
    from usar_arm.planning.collision import Contact as Contact
    from usar_arm.planning.compiled import warm_up as warm_up
    from usar_arm.planning.ik import BatchIKResult as BatchIKResult
    from usar_arm.planning.ik import IKOptions as IKOptions
    from usar_arm.planning.ik import IKResult as IKResult
    from usar_arm.planning.ik import IKSolution as IKSolution
    from usar_arm.planning.ik import IKSolver as IKSolver
    from usar_arm.planning.kinematics import KinematicModel as KinematicModel
    from usar_arm.planning.lin import LinOptions as LinOptions
    from usar_arm.planning.lin import LinPath as LinPath
    from usar_arm.planning.lin import plan_lin as plan_lin
    from usar_arm.planning.ompl_adapter import OmplOptions as OmplOptions
    from usar_arm.planning.ptp import PtpPlan as PtpPlan
    from usar_arm.planning.ptp import plan_to_joints as plan_to_joints
    from usar_arm.planning.ptp import plan_to_pose as plan_to_pose
    from usar_arm.planning.robot import Robot as Robot
    from usar_arm.planning.robot import robot_from_files as robot_from_files
    from usar_arm.planning.robot import robot_from_texts as robot_from_texts
    from usar_arm.planning.scene import Box as Box
    from usar_arm.planning.scene import CylinderShape as CylinderShape
    from usar_arm.planning.scene import Mesh as Mesh
    from usar_arm.planning.scene import Scene as Scene
    from usar_arm.planning.scene import SceneObject as SceneObject
    from usar_arm.planning.scene import Sphere as Sphere
    from usar_arm.planning.scene_file import load_scene as load_scene
    from usar_arm.planning.scene_file import parse_scene as parse_scene

__getattr__, __dir__, __all__ = exports(__name__, __file__)
