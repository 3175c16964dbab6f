"""Inverse kinematics of a tool frame: analytic where the arm allows it, numeric for any arm.

* Analytic for ortho-parallel arms with a spherical wrist (:mod:`.opw`) and for arms with three
  parallel axes like the UR family (:mod:`.ur`): all branches in closed form, each polished by
  Newton steps on the exact Pinocchio model (the learnt arm is never exactly OPW: wire rounding
  and millimetre offsets), kept when within tolerance.
* Numeric for any arm: Levenberg-Marquardt (damped least squares with adaptive damping) inside
  the joint limits, from the seed and then seeded random restarts, within a time budget.

Joints whose range is wider than 2 pi get the winding nearest the seed. Targets are 4x4 poses of
the frame in the root (base_link) frame; metres and radians.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from usar_arm.core.errors import (
    AllSolutionsInCollisionError,
    IKError,
    JointLimitError,
    UnreachableError,
)
from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ik_branches import ANALYTIC_SLACK, AnalyticBranches, Violation, Windings
from usar_arm.planning.ik_numeric import NumericIK
from usar_arm.planning.ik_types import (
    BatchIKResult,
    IKOptions,
    IKResult,
    IKSolution,
    admit,
    is_new,
)
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.planning.opw import NotOrthoParallel, OrthoParallelArm

__all__ = ["BatchIKResult", "IKOptions", "IKResult", "IKSolution", "IKSolver"]

log = logging.getLogger("usar_arm.planning")
LIMIT_CLAMP = 0.02
"""rad or m: a polished solution this close outside a limit is tried on the limit itself."""


class IKSolver:
    """IK of one frame of one arm: the public API and the judgement of candidates (limits,
    distinctness, collisions, the failure to raise). The closed-form branches and windings are
    :mod:`.ik_branches`', the Newton and Levenberg-Marquardt steps :mod:`.ik_numeric`'s.

    Args:
        chain: the robot description (joint limits, axes for the analytic structure).
        kinematics: the Pinocchio model of the same URDF.
        frame: the link whose pose is solved for (default ``tool0``).
        options: tolerances, budget, seed.
    """

    def __init__(self, chain: KinematicChain, kinematics: KinematicModel, frame: str = "tool0",
                 options: IKOptions | None = None):
        self.chain = chain
        self.kin = kinematics
        self.options = options or IKOptions()
        self.frame = chain.frames.get(frame, frame)
        self.names = chain.joint_names
        self.windings = Windings(chain)
        self.lower, self.upper = self.windings.lower, self.windings.upper
        self.revolute, self.wide = self.windings.revolute, self.windings.wide
        self.numeric = NumericIK(chain, kinematics, self.frame, self.windings, self.options)
        self.branches: AnalyticBranches | None = None
        self.analytic_reason = ""
        if self.options.use_analytic:
            try:
                self.branches = AnalyticBranches(chain, self.frame, self.windings)
            except NotOrthoParallel as exc:
                self.analytic_reason = str(exc)
                log.info("analytic IK not available for %s: %s", chain.name, exc)

    @property
    def analytic(self) -> OrthoParallelArm | None:
        """The arm's ortho-parallel closed form, or None when it is not ortho-parallel (a
        three-parallel arm's is ``branches.ur``)."""
        return None if self.branches is None else self.branches.arm

    def reseed(self, seed: int | None = None) -> None:
        """Restart the numeric search's random restarts from ``seed`` (default: the options'
        seed), so the next query's answer does not depend on the queries before it."""
        self.numeric.reseed(self.options.seed if seed is None else seed)

    @property
    def method(self) -> str:
        """``analytic`` (the ortho-parallel closed form), ``analytic-ur`` (the closed form of
        three parallel axes) or ``numeric``."""
        if self.branches is None:
            return "numeric"
        return "analytic" if self.branches.kind == "opw" else "analytic-ur"

    def solve(self, target: Array, seed: Array | None = None, all_solutions: bool = False,
              collision: CollisionWorld | None = None) -> IKResult:
        """Solutions for a target pose (4x4, root frame).

        With ``all_solutions`` every distinct solution inside the limits (analytic arms: every
        branch; others: those found within the time budget); otherwise the one nearest
        ``seed`` (nearest the zero configuration without one). With ``collision``, solutions in
        collision are dropped.

        Raises:
            UnreachableError: no configuration reaches the target (with the distance).
            JointLimitError: every solution needs a joint beyond its limits.
            AllSolutionsInCollisionError: every solution inside the limits collides.
        """
        start = time.perf_counter()
        collided: list[Array] = []
        rot = np.ascontiguousarray(target[:3, :3], dtype=float)
        pos = np.ascontiguousarray(target[:3, 3], dtype=float)
        ref = (np.zeros(len(self.names)) if seed is None
               else np.ascontiguousarray(seed, dtype=float))
        if self.branches is not None and not all_solutions:
            fast = self._nearest_compiled(rot, pos, ref, collision)
            if fast is not None:
                return IKResult((fast,), time.perf_counter() - start, f"{self.method}+newton")
        sols: list[IKSolution] = []
        violation: Violation | None = None
        starts: list[Array] = []
        method = "numeric"
        if self.branches is not None:
            sols, violation, starts = self._solve_analytic(rot, pos, ref, all_solutions,
                                                           collision, collided)
            method = f"{self.method}+newton"
        if not sols and not (self.branches is not None and collided):
            # (an arm with a closed form has no solutions beyond its branches: when they all
            # collide, searching numerically would only find them again)
            sols = self.numeric.search(rot, pos, ref, seed is not None, all_solutions,
                                       collision, start, starts, collided)
            method = "numeric" if self.branches is None else f"{self.method}+numeric"
        if not sols:
            self._raise_failure(rot, pos, ref, violation, collision, collided, start)
        sols.sort(key=lambda s: float(np.sum((s.q - ref) ** 2)))
        return IKResult(tuple(sols), time.perf_counter() - start, method)

    def _nearest_compiled(self, rot: Array, pos: Array, ref: Array,
                          collision: CollisionWorld | None) -> IKSolution | None:
        """The nearest analytic solution by the compiled path, or None when the Python path
        must decide (a singular wrist, a limit, no branch, a collision)."""
        assert self.branches is not None
        found = self.branches.nearest_compiled(rot, pos, ref, self.options)
        if found is None:
            return None
        q, pe, re = found
        if collision is not None and collision.in_collision(q):
            return None  # the Python path goes on to the next branch and reports collisions
        q.setflags(write=False)
        return IKSolution(q, pe, re)

    def nearest(self, target: Array, seed: Array | None = None) -> IKSolution:
        """The solution nearest ``seed``."""
        return self.solve(target, seed).best

    def solve_batch(self, targets: Array, seeds: Array | None = None) -> BatchIKResult:
        """The solution nearest its seed for each of N targets (N, 4, 4), vectorised.

        Analytic arms: the compiled nearest-branch path per target (about 7 us each); the
        few targets left (if any) go through :meth:`solve`.
        Other arms: :meth:`solve` per target. Failures are marked, not raised.
        """
        start = time.perf_counter()
        targets = np.asarray(targets, float).reshape(-1, 4, 4)
        n = len(targets)
        dof = len(self.names)
        refs = np.zeros((n, dof)) if seeds is None else np.broadcast_to(
            np.asarray(seeds, float), (n, dof))
        q_out = np.full((n, dof), np.nan)
        errs = np.full((n, 2), np.nan)
        done = np.zeros(n, dtype=bool)
        if self.branches is not None:  # the compiled nearest-branch path, one target at a time
            rots = np.ascontiguousarray(targets[:, :3, :3])
            poss = np.ascontiguousarray(targets[:, :3, 3])
            refs_c = np.ascontiguousarray(refs)
            for k in range(n):
                fast = self._nearest_compiled(rots[k], poss[k], refs_c[k], None)
                if fast is not None:
                    q_out[k], errs[k], done[k] = fast.q, (fast.position_error,
                                                          fast.orientation_error), True
        for i in np.flatnonzero(~done):
            try:
                sol = self.solve(targets[i], refs[i]).best
            except IKError:
                continue
            q_out[i], errs[i], done[i] = sol.q, (sol.position_error, sol.orientation_error), True
        return BatchIKResult(q_out, done, errs[:, 0], errs[:, 1], time.perf_counter() - start)

    def _solve_analytic(self, rot: Array, pos: Array, ref: Array, all_solutions: bool,
                        collision: CollisionWorld | None, collided: list[Array] | None = None,
                        ) -> tuple[list[IKSolution], Violation | None, list[Array]]:
        """The branches nearest ``ref`` first (:meth:`.AnalyticBranches.ordered`), each
        polished on the exact model and judged: the limits (a hair outside: held on the limit),
        distinctness, collisions (appended to ``collided``). Also returns the worst violation
        when nothing was found, and every branch tried (starts for the numeric search)."""
        assert self.branches is not None
        collided = [] if collided is None else collided
        found: list[IKSolution] = []
        violation: Violation | None = None
        tried: list[Array] = []
        outside: list[Array] = []
        for q in self.branches.ordered(rot, pos, ref):
            tried.append(np.array(q))
            bad = self.windings.violation(q)
            if bad is not None and bad.excess > ANALYTIC_SLACK:
                violation = _least(violation, bad)
                outside.append(np.array(q))
                continue  # clearly outside: polished on the limits only if nothing else is
            sol = self.numeric.polish(np.array(q), rot, pos)
            if sol is None:
                continue
            kept, bad = self.numeric.settle(sol, ref, rot, pos, clamp=LIMIT_CLAMP)
            if kept is None:
                assert bad is not None
                violation = _least(violation, bad)
                continue
            if admit(kept, found, self.options.distinct, collision, collided) \
                    and not all_solutions:
                break
        if not found:
            self._on_the_limits(outside, rot, pos, ref, all_solutions, collision, collided, found)
        return found, (violation if not found else None), tried

    def _on_the_limits(self, outside: list[Array], rot: Array, pos: Array, ref: Array,
                       all_solutions: bool, collision: CollisionWorld | None,
                       collided: list[Array], found: list[IKSolution]) -> None:
        """Branches far outside the limits, held on the limits they cross and Newton on the
        other joints (:meth:`.NumericIK.clamped`), appended to ``found``: near a singularity
        (the KR60 folded with its wrist centre near axis 2) a closed form fitted to the arm
        can land tenths of a radian away from the exact solution on a limit."""
        for q in outside:
            sol = self.numeric.clamped(q, rot, pos)
            if sol is not None and self.numeric.keep(sol, ref, found, all_solutions, collision,
                                                     collided):
                return

    def _raise_failure(self, rot: Array, pos: Array, ref: Array, violation: Violation | None,
                       collision: CollisionWorld | None, collided: list[Array],
                       start: float) -> None:
        """Raise the error that says why no solution was kept."""
        if collision is not None and collided:
            distinct: list[Array] = []
            for q in collided:
                if is_new(q, distinct, self.options.distinct):
                    distinct.append(q)
            pairs = sorted({p for q in distinct for p in collision.contacts(q)})
            raise AllSolutionsInCollisionError(len(distinct), pairs)
        if violation is not None:
            i = violation.index
            raise JointLimitError(self.names[i], violation.value, float(self.lower[i]),
                                  float(self.upper[i]))
        distance = self.numeric.closest_approach(rot, pos, ref)
        raise UnreachableError(distance, f"no {self.method} solution within "
                               f"{self.options.position_tolerance:g} m / "
                               f"{self.options.orientation_tolerance:g} rad after "
                               f"{time.perf_counter() - start:.3f} s")


def _least(worst: Violation | None, bad: Violation) -> Violation:
    """The smaller of two limit violations (the one a user can act on)."""
    return bad if worst is None or bad.excess < worst.excess else worst
