"""Planning a motion and timing it: the PTP/LIN layer shared by the CLI and the Arm facade.

PTP: OMPL path in joint space (to a configuration, or to the best reachable IK solution of a
tool0 pose), then Ruckig segments (rest at every waypoint, or blended). LIN: straight tool0 line
by IK at every step, then one jerk-limited profile along it. Velocity, acceleration and jerk
limits come from the description, scaled by ``speed_scale``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from usar_arm.control.timing import (
    DEFAULT_RATE_HZ,
    TimedMotion,
    along_path,
    blended,
    stop_at_waypoints,
)
from usar_arm.control.trajectory import MotionLimits, Trajectory
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.inputs import check_pose, joint_vector
from usar_arm.core.spatial import Array, rotation_distance
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.lin import LinOptions, plan_lin
from usar_arm.planning.ompl_adapter import OmplOptions
from usar_arm.planning.ptp import check_state, plan_to_joints, plan_to_pose
from usar_arm.planning.robot import Robot

MOTIONS = ("ptp", "lin")


@dataclass(frozen=True)
class MotionOptions:
    """How to plan and time a motion.

    Attributes:
        motion: ``ptp`` (joint space) or ``lin`` (straight tool0 line).
        ompl: planner, time limit, edge resolution, seed (PTP).
        lin: step sizes and the branch-flip threshold (LIN).
        speed_scale: fraction (0, 1] of the velocity, acceleration and jerk limits used.
        blend: PTP passes through its waypoints instead of stopping at each.
        rate: samples per second of the returned trajectory (>= 250).
        cartesian_speed, cartesian_acceleration: LIN tool limits (m/s, m/s^2) before scaling
            (MoveIt Pilz defaults).
    """

    motion: str = "ptp"
    ompl: OmplOptions = field(default_factory=OmplOptions)
    lin: LinOptions = field(default_factory=LinOptions)
    speed_scale: float = 0.5
    blend: bool = False
    rate: float = DEFAULT_RATE_HZ
    cartesian_speed: float = 1.0
    cartesian_acceleration: float = 2.25

    def __post_init__(self) -> None:
        if self.motion not in MOTIONS:
            raise InvalidInputError(f"motion must be ptp or lin, got '{self.motion}'")
        if not 0 < self.speed_scale <= 1:
            raise InvalidInputError(f"speed scale must be in (0, 1], got {self.speed_scale}")
        if self.rate < 250:
            raise InvalidInputError(f"trajectory rate must be >= 250 Hz, got {self.rate}")


@dataclass(frozen=True)
class MotionPlan:
    """A planned, timed motion.

    Attributes:
        trajectory: the samples to execute. waypoints: the geometric path (collision-checked).
        goal: the goal configuration. goal_pose: the tool0 target, for pose goals.
        planning_seconds: path planning (incl. IK and simplification).
        timing_seconds: time-parameterisation. path_length: joint-space length (rad).
    """

    trajectory: Trajectory
    waypoints: Array
    goal: Array
    goal_pose: Array | None
    planning_seconds: float
    timing_seconds: float
    path_length: float
    motion: str
    details: dict[str, Any] = field(default_factory=dict)
    timed: TimedMotion | None = None
    """The continuous-time motion the trajectory samples (evaluate it at any rate)."""

    def summary(self) -> dict[str, Any]:
        """The stable keys ``usar-arm plan --json`` prints."""
        return {"motion": self.motion, "planning_seconds": self.planning_seconds,
                "timing_seconds": self.timing_seconds, "duration": self.trajectory.duration,
                "path_length": self.path_length, "waypoints": len(self.waypoints),
                "mode": self.trajectory.mode, **self.details}


def plan_motion(robot: Robot, world: CollisionWorld, start: Array, *,
                goal: Array | None = None, pose: Array | None = None,
                options: MotionOptions = MotionOptions()) -> MotionPlan:
    """Plan and time a motion from ``start`` to a configuration ``goal`` or a tool0 ``pose``
    (4x4 in base_link).

    Raises:
        InvalidInputError: a goal that is neither joints nor a pose, or both.
        OutOfLimitsError: the start or goal outside the joint limits.
        StartInCollisionError: the start in collision (the pairs named).
        GoalInCollisionError: the goal in collision (the pairs named).
        IKError: no collision-free IK solution of the goal pose.
        NoPathError: no path within the time limit.
        LinBlockedError: a straight line that cannot be followed (where, and why).
        TimingError: the path could not be timed within the limits.
    """
    if (goal is None) == (pose is None):
        raise InvalidInputError("give exactly one of a goal configuration or a goal pose")
    chain = robot.chain
    names = chain.joint_names
    start = joint_vector(start, names, "the start", named=False)
    if goal is not None:
        goal = joint_vector(goal, names, "the goal")
    if pose is not None:
        pose = check_pose(pose)
    limits = MotionLimits.from_chain(chain, options.speed_scale)
    ik = robot.ik_solver()
    begin = time.perf_counter()
    details: dict[str, Any] = {}
    if options.motion == "ptp":
        if pose is not None:
            plan = plan_to_pose(world, ik, start, pose, options.ompl)
            details["ik_solutions_tried"] = plan.goals_tried
        else:
            assert goal is not None  # exactly one of goal and pose, checked above
            plan = plan_to_joints(world, names, chain.lower(), chain.upper(), start, goal,
                                  options.ompl)
        if plan.ompl is not None:
            details.update(planner=plan.ompl.planner, simplify_seconds=plan.ompl.simplify_seconds,
                           states_checked=plan.ompl.states_checked,
                           edges_checked=plan.ompl.edges_checked,
                           dense_replans=plan.dense_replans, repaired=plan.repaired)
        else:
            details["planner"] = "direct (the straight joint-space segment is free)"
        planning = time.perf_counter() - begin
        waypoints, goal_q = plan.waypoints, plan.goal
        timed = (blended(names, waypoints, limits, world.in_collision_many,
                         check_step=1.0 / options.rate)
                 if options.blend else stop_at_waypoints(names, waypoints, limits))
    else:
        check_state(world, names, chain.lower(), chain.upper(), start, "start")
        start_pose = robot.kinematics.frame_pose(start, "tool0")
        if pose is not None:
            target = pose
        else:
            assert goal is not None  # exactly one of goal and pose, checked above
            target = robot.kinematics.frame_pose(goal, "tool0")
        path = plan_lin(ik, world, start, start_pose, target, options.lin)
        planning = time.perf_counter() - begin
        waypoints, goal_q = path.q, path.q[-1]
        scale = options.speed_scale
        timed = along_path(names, path.s, path.q, limits, options.cartesian_speed * scale,
                           options.cartesian_acceleration * scale)
        details["line_length_m"] = path.length
    trajectory = timed.sample(options.rate, options.motion)
    if not trajectory.duration > 0:
        trajectory = _holding(trajectory, options.rate)
    if pose is not None:
        final = robot.kinematics.frame_pose(trajectory.q[-1], "tool0")
        details["final_position_error_m"] = float(np.linalg.norm(final[:3, 3] - pose[:3, 3]))
        details["final_orientation_error_rad"] = rotation_distance(final[:3, :3], pose[:3, :3])
    length = float(np.sum(np.linalg.norm(np.diff(waypoints, axis=0), axis=1)))
    info = dict(trajectory.info)
    info.update(planning_seconds=planning, path_length=length)
    trajectory = Trajectory(trajectory.joint_names, trajectory.t, trajectory.q, trajectory.qd,
                            trajectory.qdd, trajectory.waypoints, trajectory.limits,
                            trajectory.motion, trajectory.mode, info)
    return MotionPlan(trajectory, waypoints, goal_q, pose, planning, timed.seconds, length,
                      options.motion, details, timed)


def _holding(trajectory: Trajectory, rate: float) -> Trajectory:
    """A motion that does not move (the goal is the start) as two samples one period apart at
    rest: a trajectory's sample times must increase (a file with t = [0, 0] could not be read
    back, and its rate would be infinite)."""
    q = np.vstack([trajectory.q[0], trajectory.q[0]])
    zero = np.zeros_like(q)
    return Trajectory(trajectory.joint_names, np.array([0.0, 1.0 / rate]), q, zero, zero.copy(),
                      trajectory.waypoints, trajectory.limits, trajectory.motion,
                      trajectory.mode, trajectory.info)
