"""A pick-and-place cycle in the ``table`` scene: the demo's job, also timed by the benchmarks.

Seven moves, in the KUKA/Pilz vocabulary: PTP to above the part, LIN down to it, LIN up, PTP
around the tower to above the bin, LIN down into it, LIN up, PTP home. Each move is planned from
where the arm really is, executed, and measured; :func:`run_cycle` returns one row per move.
The moves say where the vacuum grips (``then="grip"``, after the pick) and releases
(``then="release"``, after the place); :mod:`usar_arm.arm.pick_place` acts on them with the
simulator's vacuum and WorldController, :func:`run_cycle` ignores them (a cycle that mimes).

The targets are the tool's: the suction cup's centre (the description's ``tcp`` frame,
``KR60gripper_tcp``) pointing straight down; each move's ``pose`` is tool0's (m, rad, base_link),
taken from the tool's through the tool0 -> TCP transform of the arm's description.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from usar_arm.arm.facade import Arm
from usar_arm.control.executor import ExecutionOptions, ExecutionReport
from usar_arm.control.motion import MotionOptions, MotionPlan
from usar_arm.control.splice import join_executed, join_trajectories
from usar_arm.control.trajectory import ExecutedSamples, Trajectory
from usar_arm.core.spatial import Array, invert, rpy_to_matrix, transform
from usar_arm.planning.robot import Robot

TOOL_DOWN = rpy_to_matrix((0.0, np.pi, 0.0))
"""The tool's orientation with its z axis pointing down (REP-103 base_link)."""
PICK = (1.45, -0.45)
"""The part's centre (x, y; m) on the table scene's table."""
PLACE = (1.45, 0.50)
"""The bin's centre (x, y; m): where the part is put."""
GAP = 0.02
"""How far (m) the suction cup stops above the part's top: inside the vacuum's suction zone
(the cup's centre to 0.125 m below it), clear of the part by the description's 8 mm worst
tool error on a UDK wire and its 10 mm print step of the tool's length."""
PART_HEIGHT = 0.10
"""The part's height (m): the table scene's WCCrate at scale 0.4."""
PICK_Z = 0.80 + GAP
"""The cup's height (m) at the pick: the part's top is at 0.80."""
RELEASE_HEIGHT = 0.015
"""How far (m) above the bin's inner floor (0.715 m) the part is let go."""
PLACE_Z = 0.715 + RELEASE_HEIGHT + PART_HEIGHT + GAP
"""The cup's height (m) at the place, the gripper inside the bin (its rim is at 0.90)."""
CLEAR_Z = 1.10
"""The cup's height (m) above the part and the bin: a carried part's bottom 0.08 m above the
bin's rim."""
TCP_FRAMES = ("tcp", "KR60gripper_tcp")
"""Where the tool's centre point is: the description's frame role (a learnt description's
discovery notes name it), else the KR60's TCP link (a description read from its URDF alone,
such as a ROS node's ``robot_description``)."""


@dataclass(frozen=True)
class Move:
    """One move of a cycle: a tool0 ``pose`` (4x4) or joint values ``joints``; ``then``: what
    the vacuum does once the arm is there (``grip``, ``release`` or nothing)."""

    name: str
    motion: str
    pose: Array | None = None
    joints: Array | None = None
    then: str | None = None


def tcp_offset(robot: Robot, frames: tuple[str, ...] = TCP_FRAMES) -> Array:
    """tool0 -> the tool's centre point (4x4) in ``robot``'s description (the first of
    ``frames`` it has); identity when it describes no tool (the targets are then tool0's)."""
    kin = robot.kinematics
    q = np.array(robot.home())
    for frame in frames:
        try:
            tool = kin.frame_pose(q, frame)
        except KeyError:
            continue
        out: Array = invert(kin.frame_pose(q, "tool0")) @ tool
        return out
    return np.eye(4)


def pick_and_place(home: Array, tcp: Array | None = None) -> list[Move]:
    """The table scene's cycle, ending at ``home`` (joint values); ``tcp``: tool0 -> the
    tool's centre point (:func:`tcp_offset`; identity: the targets are tool0's)."""
    to_tool0 = invert(np.eye(4) if tcp is None else np.asarray(tcp, float))

    def at(xy: tuple[float, float], z: float) -> Array:
        out: Array = transform(TOOL_DOWN, (xy[0], xy[1], z)) @ to_tool0
        return out

    return [Move("approach", "ptp", at(PICK, CLEAR_Z)),
            Move("pick", "lin", at(PICK, PICK_Z), then="grip"),
            Move("lift", "lin", at(PICK, CLEAR_Z)),
            Move("transfer", "ptp", at(PLACE, CLEAR_Z)),
            Move("place", "lin", at(PLACE, PLACE_Z), then="release"),
            Move("retreat", "lin", at(PLACE, CLEAR_Z)),
            Move("home", "ptp", joints=np.asarray(home, float))]


def through(targets: list[tuple[str, Array]], home: Array) -> list[Move]:
    """A cycle that visits named tool0 poses (4x4, base_link) in order by PTP moves and ends
    at ``home`` (joint values): e.g. the targets of a placement study, from its best base."""
    return [*(Move(name, "ptp", pose) for name, pose in targets),
            Move("home", "ptp", joints=np.asarray(home, float))]


@dataclass
class MoveResult:
    """What one move did: its plan, its execution report, and the wall time it took (s)."""

    move: Move
    plan: MotionPlan
    report: ExecutionReport
    seconds: float

    def row(self) -> dict[str, Any]:
        """The figures the demo's table and the benchmark print (SI units)."""
        tip = self.report.tip.as_json() if self.report.tip is not None else {}
        return {"move": self.move.name, "motion": self.move.motion,
                "planning_s": self.plan.planning_seconds,
                "duration_s": self.plan.trajectory.duration,
                "max_tracking_error_rad": self.report.max_tracking_error_rad,
                "final_joint_error_rad": float(np.max(self.report.final_joint_error_rad)),
                "rate_hz": self.report.rate_hz, "jitter_p99_ms": self.report.jitter_p99_ms,
                "tip_source": tip.get("tip_source"),
                "tip_error_m": tip.get("tip_error_m"), "tip_error_rad": tip.get("tip_error_rad"),
                "tip_error_before_correction_m": tip.get("tip_error_before_correction_m"),
                "tip_error_before_correction_rad": tip.get("tip_error_before_correction_rad"),
                "true_tip_error_m": tip.get("true_tip_error_m"),
                "true_tip_error_rad": tip.get("true_tip_error_rad"),
                "wall_s": self.seconds}


@dataclass
class CycleResult:
    """Every move's result, in order."""

    moves: list[MoveResult] = field(default_factory=list)

    def rows(self) -> list[dict[str, Any]]:
        """One :meth:`MoveResult.row` per move."""
        return [m.row() for m in self.moves]

    def timeline(self) -> tuple[Trajectory, ExecutedSamples]:
        """The whole cycle as one trajectory (holding still between the moves, while the next
        one was planned and the arm settled) and its ASTA samples, from the first move's
        start (s)."""
        starts = [m.report.started_at for m in self.moves]
        planned = join_trajectories([(s, m.plan.trajectory)
                                     for s, m in zip(starts, self.moves, strict=True)])
        executed = join_executed([(s, m.report.executed)
                                  for s, m in zip(starts, self.moves, strict=True)], starts[0])
        return planned, executed


def run_cycle(arm: Arm, moves: list[Move], scene: str = "table",
              motion: MotionOptions | None = None, execution: ExecutionOptions | None = None,
              tip_correction: bool = False,
              progress: Callable[[int, MoveResult], None] | None = None) -> CycleResult:
    """Plan each move from the arm's current joints, execute it, and measure it.

    Pose moves are measured against their pose, joint moves against the model's tool0 at
    their goal; with ``tip_correction`` the real tool is brought to that pose (see
    :meth:`Arm.execute`).

    Raises:
        PlanningError: the planning errors of :func:`usar_arm.control.motion.plan_motion`,
            naming the move in a note.
        ExecutionAbortedError: as :meth:`Arm.execute`, naming the move in a note.
    """
    result = CycleResult()
    for i, move in enumerate(moves):
        begin = time.perf_counter()
        try:
            plan = arm.plan(joints=move.joints, pose=move.pose, motion=move.motion,
                            scene=scene, options=motion)
            report = arm.execute(plan.trajectory, goal_pose=move.pose, options=execution,
                                 tip_correction=tip_correction)
        except Exception as exc:
            exc.add_note(f"during move {i + 1} ({move.name}, {move.motion.upper()})")
            raise
        done = MoveResult(move, plan, report, time.perf_counter() - begin)
        result.moves.append(done)
        if progress is not None:
            progress(i, done)
    return result
