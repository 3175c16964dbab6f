"""The 1 kHz re-check of a planned motion, shared by the planning tests.

A plan is re-evaluated from its continuous-time motion every millisecond (and at its end):

* collision: every 1 ms sample through :meth:`CollisionWorld.in_collision_many` (forward
  kinematics by products of exponentials, exact FCL narrowphase behind an AABB broadphase), and
  every ``brute_force_period`` s through :meth:`CollisionWorld.contacts_brute_force` (Pinocchio
  kinematics, every checked pair, no broadphase): the reference the batched check is tested
  against;
* limits: position, velocity, acceleration and jerk (finite differences of the acceleration) of
  every joint, for the 1 ms samples and for the trajectory the plan returns (the samples an
  executor streams);
* ends: the trajectory starts at the start, at rest, and ends at rest on the goal configuration;
  a pose goal is reached within 1 mm / 1 mrad; a LIN motion keeps tool0 within 1 mm of its line.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from usar_arm.control.motion import MotionPlan
from usar_arm.control.trajectory import LimitReport, check_limits
from usar_arm.core.spatial import Array, rotation_distance
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ompl_adapter import edge_configurations
from usar_arm.planning.robot import Robot

RATE_HZ = 1000.0
LIMIT_TOLERANCE = 1e-6
"""Relative: a limit may be used up to (1 + this) of its value."""
POSITION_TOLERANCE_M = 1e-3
ORIENTATION_TOLERANCE_RAD = 1e-3
LINE_TOLERANCE_M = 1e-3
POSITION_ROUNDING = 1e-12
"""rad or m: how far a sampled position may be off its exact value by float64 rounding (values
of a few radians through a few dozen operations)."""


def finite_difference_violations(t: Array, q: Array, lower: Array, upper: Array,
                                 vmax: Array, amax: Array, jmax: Array) -> list[str]:
    """The limits checked from the positions alone (not the code's own velocities and
    accelerations, nor its limit check): over the uniform 1 ms samples, the first, second and
    third differences are weighted averages of velocity, acceleration and jerk over 1, 2 and
    3 ms, so none of them may exceed its limit. The one allowance is the positions' own
    rounding, :data:`POSITION_ROUNDING` rad, which an n-th difference divides by h^n and
    multiplies by up to 2^n (at 1 kHz: 8e-3 rad/s^3 of jerk)."""
    out = []
    if np.any(q < lower - 1e-9) or np.any(q > upper + 1e-9):
        out.append("a position outside its joint limits (samples)")
    uniform = np.flatnonzero(np.abs(np.diff(t) - 1.0 / RATE_HZ) < 1e-9)
    if len(uniform) < 4:
        return out
    k = np.arange(uniform[0], uniform[-1] + 2)  # the run of uniformly spaced samples
    h = 1.0 / RATE_HZ
    for order, limit, name in ((1, vmax, "velocity"), (2, amax, "acceleration"),
                               (3, jmax, "jerk")):
        diff = np.diff(q[k], n=order, axis=0) / h ** order
        allowance = POSITION_ROUNDING * 2 ** order / h ** order
        worst = float(np.max(np.abs(diff) / (limit * (1 + LIMIT_TOLERANCE) + allowance)))
        if worst > 1.0 + 1e-6:
            out.append(f"finite-difference {name} {worst:.6f}x its limit")
    return out


@dataclass
class Recheck:
    """What the re-check measured and every invariant it found broken (empty: all kept)."""

    samples: int = 0
    brute_force_samples: int = 0
    limits: LimitReport | None = None
    final_position_error_m: float | None = None
    final_orientation_error_rad: float | None = None
    line_deviation_m: float | None = None
    violations: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.violations


def _limits(what: str, report: LimitReport, out: list[str]) -> None:
    if not report.within(LIMIT_TOLERANCE):
        out.append(f"{what} exceeds a limit: {report}")


def recheck(robot: Robot, world: CollisionWorld, plan: MotionPlan, start: Array | None = None,
            line_start: Array | None = None, brute_force_period: float = 0.1) -> Recheck:
    """Re-check ``plan`` (from ``start``; ``line_start``: tool0 position where a LIN line
    begins) and return what was found."""
    out = Recheck()
    bad = out.violations
    names = robot.chain.joint_names
    timed = plan.timed
    traj = plan.trajectory
    if timed is None:
        bad.append("the plan carries no continuous-time motion")
        return out
    duration = timed.duration
    t = np.append(np.arange(0.0, duration, 1.0 / RATE_HZ), duration)
    t = t[np.concatenate([[True], np.diff(t) > 1e-12])]
    q, qd, qdd = timed.evaluate(t)
    out.samples = len(t)
    if not np.all(np.isfinite(q) & np.isfinite(qd) & np.isfinite(qdd)):
        bad.append("non-finite samples")
        return out
    out.limits = check_limits(t, q, qd, qdd, traj.limits, names)
    _limits("the 1 kHz motion", out.limits, bad)
    bad += finite_difference_violations(t, q, traj.limits.lower, traj.limits.upper,
                                        traj.limits.velocity, traj.limits.acceleration,
                                        traj.limits.jerk)
    hits = world.in_collision_many(q)
    if np.any(hits):
        k = int(np.argmax(hits))
        bad.append(f"collision at t = {t[k]:.3f} s ({len(np.flatnonzero(hits))} of {len(t)} "
                   f"1 kHz samples): {world.contacts(q[k])}")
    stride = max(1, round(brute_force_period * RATE_HZ))
    picks = np.unique(np.append(np.arange(0, len(t), stride), len(t) - 1))
    out.brute_force_samples = len(picks)
    for k in picks:
        pairs = world.contacts_brute_force(q[k])
        if pairs:
            bad.append(f"collision (brute force) at t = {t[k]:.3f} s: {pairs}")
            break
    # The trajectory an executor streams.
    if traj.rate < 250:
        bad.append(f"trajectory rate {traj.rate:.1f} Hz < 250 Hz")
    dt = np.diff(traj.t)
    if np.any(dt <= 0) or np.ptp(dt) > 1e-9:
        bad.append("trajectory sample times are not uniform and increasing")
    _limits("the returned trajectory", check_limits(traj.t, traj.q, traj.qd, traj.qdd,
                                                    traj.limits, names), bad)
    every = np.unique(np.append(np.arange(0, len(traj.t) - 1, 7), len(traj.t) - 1))
    tq, tqd, _ = timed.evaluate(traj.t[every])
    if not np.allclose(traj.q[every], tq, atol=1e-9) or not np.allclose(
            traj.qd[every[:-1]], tqd[:-1], atol=1e-9):
        bad.append("the returned samples differ from the continuous motion")
    if start is not None and not np.allclose(traj.q[0], start, atol=1e-9):
        bad.append(f"starts at {traj.q[0]}, not at the start {start}")
    if not (np.allclose(traj.qd[[0, -1]], 0.0, atol=1e-9)
            and np.allclose(qd[[0, -1]], 0.0, atol=1e-6)):
        bad.append("does not start and end at rest")
    if not np.allclose(traj.q[-1], plan.goal, atol=1e-9):
        bad.append(f"ends at {traj.q[-1]}, not at the goal {plan.goal}")
    if plan.goal_pose is not None:
        final = robot.kinematics.frame_pose(traj.q[-1], "tool0")
        out.final_position_error_m = float(np.linalg.norm(final[:3, 3] - plan.goal_pose[:3, 3]))
        out.final_orientation_error_rad = rotation_distance(final[:3, :3],
                                                            plan.goal_pose[:3, :3])
        if (out.final_position_error_m > POSITION_TOLERANCE_M
                or out.final_orientation_error_rad > ORIENTATION_TOLERANCE_RAD):
            bad.append(f"final tool0 is {out.final_position_error_m * 1000:.3f} mm / "
                       f"{out.final_orientation_error_rad * 1000:.3f} mrad from the goal pose")
    if plan.motion == "lin" and line_start is not None:
        end = robot.kinematics.frame_pose(plan.goal, "tool0")[:3, 3]
        step = max(1, round(0.005 * RATE_HZ))
        tips = np.array([robot.kinematics.frame_pose(x, "tool0")[:3, 3] for x in q[::step]])
        out.line_deviation_m = _line_distance(tips, np.asarray(line_start, float), end)
        if out.line_deviation_m > LINE_TOLERANCE_M:
            bad.append(f"tool0 leaves its line by {out.line_deviation_m * 1000:.3f} mm")
    return out


def _line_distance(points: Array, a: Array, b: Array) -> float:
    """Largest distance (m) of ``points`` from the segment a-b."""
    ab = b - a
    denom = float(ab @ ab)
    s = np.zeros(len(points)) if denom < 1e-18 else np.clip((points - a) @ ab / denom, 0, 1)
    return float(np.max(np.linalg.norm(points - (a + s[:, None] * ab), axis=1)))


def assert_rechecked(robot: Robot, world: CollisionWorld, plan: MotionPlan,
                     start: Array | None = None, line_start: Array | None = None) -> Recheck:
    """:func:`recheck`, failing the test on any violation."""
    result = recheck(robot, world, plan, start, line_start)
    assert result.ok, "\n".join(result.violations)
    return result


def blocked_pairs(world: CollisionWorld, robot: Robot, count: int, seed: int
                  ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Free start/goal pairs whose straight joint-space segment is blocked (a planner needed),
    drawn uniformly within the limits from ``seed``."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        a, b = rng.uniform(robot.chain.lower(), robot.chain.upper(), size=(2, robot.chain.dof))
        if world.in_collision(a) or world.in_collision(b):
            continue
        if world.in_collision_many(edge_configurations(a, b, 0.01)).any():
            out.append((a, b))
    return out
