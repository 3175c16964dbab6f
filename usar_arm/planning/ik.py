"""Inverse kinematics of a tool frame: analytic where the arm allows it, numeric for any arm.

* Analytic (:mod:`.opw`) for ortho-parallel arms with a spherical wrist: all branches in closed
  form, each polished by Newton steps on the exact Pinocchio model (the learnt arm is never
  exactly OPW: wire rounding and millimetre offsets), kept when within tolerance.
* Numeric for any arm: Levenberg-Marquardt (damped least squares with adaptive damping) inside
  the joint limits, from the seed and then seeded random restarts, within a time budget.

Joints whose range is wider than 2 pi get the winding nearest the seed. Targets are 4x4 poses of
the frame in the root (base_link) frame; metres and radians.
"""

from __future__ import annotations

import heapq
import logging
import math
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.linalg.lapack import dgesv

from usar_arm.core.errors import (
    AllSolutionsInCollisionError,
    IKError,
    JointLimitError,
    UnreachableError,
)
from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning import ik_kernel
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.planning.opw import NotOrthoParallel, OrthoParallelArm
from usar_arm.planning.poe import PoeChain, PoeModel

log = logging.getLogger("usar_arm.planning")
TWO_PI = 2.0 * math.pi
LM_ITERATIONS = 25
"""Iterations of one Levenberg-Marquardt attempt before a random restart."""
LM_DAMPING = 0.01
LM_FLOOR = 1e-4
MAX_LM_STEP = 0.5
"""rad or m: the largest joint change of one LM step."""
WRIST_SINGULAR = 0.05
"""|sin q5| below which the wrist is treated as (nearly) singular."""
LIMIT_CLAMP = 0.02
"""rad or m: a polished solution this close outside a limit is tried on the limit itself."""
MAX_NEWTON_STEP = 0.3
"""rad or m: the largest joint change of one polishing step."""
ANALYTIC_SLACK = 0.05
"""rad: an analytic branch this close outside a limit is still polished (the closed form is only
approximate on the real arm, so the exact solution may lie inside)."""


@dataclass(frozen=True)
class IKOptions:
    """Options of the IK solver.

    Attributes:
        position_tolerance: m. orientation_tolerance: rad. A solution is accepted when the
            frame is within both of the target.
        time_budget: s for the numeric search (per query).
        newton_steps: at most this many polishing steps per analytic branch.
        seed: seed of the random restarts (deterministic by default).
        distinct: rad; solutions closer than this on every joint are the same solution.
        use_analytic: try the closed form when the arm is in the OPW class.
    """

    position_tolerance: float = 1e-5
    orientation_tolerance: float = 1e-5
    time_budget: float = 0.05
    newton_steps: int = 8
    seed: int = 0
    distinct: float = 1e-3
    use_analytic: bool = True


@dataclass(frozen=True)
class IKSolution:
    """One configuration (rad/m, read-only array) and how far its frame is from the target."""

    q: Array
    position_error: float
    orientation_error: float


@dataclass(frozen=True)
class BatchIKResult:
    """Results of :meth:`IKSolver.solve_batch`: q (N, n; NaN where failed), success (N,),
    position/orientation errors (m, rad; NaN where failed), and the total time (s)."""

    q: Array
    success: Array
    position_error: Array
    orientation_error: Array
    seconds: float


@dataclass(frozen=True)
class IKResult:
    """Solutions, best first (nearest the seed when one was given), and the time taken (s)."""

    solutions: tuple[IKSolution, ...]
    seconds: float
    method: str

    @property
    def best(self) -> IKSolution:
        """The first solution."""
        return self.solutions[0]


def _dist(q: list[float], ref: list[float], start: int, stop: int) -> float:
    """Squared distance of joints start..stop (q holds joints from 0 or from start)."""
    off = 0 if len(q) == stop else start
    return sum((q[i - off] - ref[i]) ** 2 for i in range(start, stop))


@dataclass(frozen=True)
class _Violation:
    """Joint ``index`` at ``value`` lies ``excess`` beyond its limits."""

    index: int
    value: float
    excess: float


def _frozen(q: Array) -> Array:
    out = np.array(q, dtype=float)
    out.setflags(write=False)
    return out


class _ChainArrays(NamedTuple):
    """The serial chain as the compiled kernels take it (:mod:`.ik_kernel`): joint axes and
    points at zero (n, 3), 1.0 for revolute joints, the frame's pose at zero (4, 4)."""

    axes: Array
    points: Array
    revolute: Array
    tool: Array


class _AnalyticArrays(NamedTuple):
    """What :func:`.ik_kernel.nearest` takes besides the query."""

    constants: Array
    lower: Array
    upper: Array
    revolute: Array
    wide: Array
    axes: Array
    points: Array
    tool: Array


class IKSolver:
    """IK of one frame of one arm.

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
        self.fid = kinematics.frame_id(self.frame)
        self.lower = chain.lower()
        self.upper = chain.upper()
        self.names = chain.joint_names
        self.wide: NDArray[np.bool_] = (self.upper - self.lower) > TWO_PI + 1e-9
        self.revolute: NDArray[np.bool_] = np.array(
            [j.type.value == "revolute" for j in chain.actuated_joints], dtype=bool)
        self._lo = [float(v) for v in self.lower]
        self._hi = [float(v) for v in self.upper]
        self._rev = [bool(v) for v in self.revolute]
        self._wide = [bool(v) for v in self.wide]
        self.wide_any = any(self._wide)
        self._diag = np.arange(len(self.names)) * (len(self.names) + 1)
        self.analytic: OrthoParallelArm | None = None
        self.analytic_reason = ""
        if self.options.use_analytic:
            try:
                self.analytic = self._build_analytic()
            except NotOrthoParallel as exc:
                self.analytic_reason = str(exc)
                log.info("analytic IK not available for %s: %s", chain.name, exc)
        self._rng = np.random.default_rng(self.options.seed)
        self._poe: PoeChain | None = None
        self._fast: _AnalyticArrays | None = None
        self._chain_arrays: _ChainArrays | None = None
        try:
            poe = PoeModel(chain)
            if poe.joints_moving(self.frame) == poe.dof:
                self._chain_arrays = _ChainArrays(
                    poe.axes, poe.points, poe.revolute.astype(float),
                    np.ascontiguousarray(chain.frame_pose(self.frame, np.zeros(chain.dof))))
        except ValueError:  # not one serial path to the frame: Pinocchio's LM only
            pass
        if self.analytic is not None:
            poe = PoeModel(chain)
            self._fast = _AnalyticArrays(
                ik_kernel.pack(self.analytic), self.lower, self.upper,
                self.revolute.astype(float), self.wide.astype(float), poe.axes, poe.points,
                np.ascontiguousarray(chain.frame_pose(self.frame, np.zeros(6))))

    def reseed(self, seed: int | None = None) -> None:
        """Restart the numeric search's random restarts from ``seed`` (default: the options'
        seed), so the next query's answer does not depend on the queries before it."""
        self._rng = np.random.default_rng(self.options.seed if seed is None else seed)

    def _build_analytic(self) -> OrthoParallelArm:
        if not all(self.revolute) or len(self.names) != 6:
            raise NotOrthoParallel("needs exactly 6 revolute joints")
        zero = np.zeros(len(self.names))
        frames = [(j, f) for j, f in self.chain.joint_frames(zero) if j.actuated]
        axes = np.array([f[:3, :3] @ np.asarray(j.axis) for j, f in frames])
        points = np.array([f[:3, 3] for _, f in frames])
        return OrthoParallelArm(axes, points, self.chain.frame_pose(self.frame, zero))

    @property
    def method(self) -> str:
        """``analytic`` or ``numeric``."""
        return "analytic" if self.analytic is not None else "numeric"

    # ------------------------------------------------------------------ public API
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
        self._collided: list[Array] = []
        rot = np.ascontiguousarray(target[:3, :3], dtype=float)
        pos = np.ascontiguousarray(target[:3, 3], dtype=float)
        ref = (np.zeros(len(self.names)) if seed is None
               else np.ascontiguousarray(seed, dtype=float))
        if self._fast is not None and not all_solutions:
            fast = self._nearest_compiled(rot, pos, ref, collision)
            if fast is not None:
                return IKResult((fast,), time.perf_counter() - start, "analytic+newton")
        sols: list[IKSolution] = []
        violation: _Violation | None = None
        starts: list[Array] = []
        method = "numeric"
        if self.analytic is not None:
            sols, violation, starts = self._solve_analytic(rot, pos, ref, all_solutions,
                                                           collision)
            method = "analytic+newton"
        if not sols and not (self.analytic is not None and self._collided):
            # (an arm with a closed form has no solutions beyond its branches: when they all
            # collide, searching numerically would only find them again)
            sols = self._solve_numeric(rot, pos, ref, seed is not None, all_solutions,
                                       collision, start, starts)
            method = "numeric" if self.analytic is None else "analytic+numeric"
        if not sols:
            self._raise_failure(rot, pos, ref, violation, collision, start)
        sols.sort(key=lambda s: float(np.sum((s.q - ref) ** 2)))
        return IKResult(tuple(sols), time.perf_counter() - start, method)

    def _nearest_compiled(self, rot: Array, pos: Array, ref: Array,
                          collision: CollisionWorld | None) -> IKSolution | None:
        """The nearest analytic solution by the compiled path (:mod:`.ik_kernel`), or None
        when the Python path must decide (a singular wrist, a limit, no branch, a collision)."""
        assert self._fast is not None
        q = np.empty(len(self.names))
        opts = self.options
        f = self._fast
        status, pe, re = ik_kernel.nearest(
            rot, pos, ref, f.constants, f.lower, f.upper, f.revolute, f.wide, f.axes, f.points,
            f.tool, opts.position_tolerance, opts.orientation_tolerance, opts.newton_steps,
            MAX_NEWTON_STEP, ANALYTIC_SLACK, WRIST_SINGULAR, q)
        if status != ik_kernel.SOLVED:
            return None
        if collision is not None and collision.in_collision(q):
            return None  # the Python path goes on to the next branch and reports collisions
        q.setflags(write=False)
        return IKSolution(q, pe, re)

    def nearest(self, target: Array, seed: Array | None = None) -> IKSolution:
        """The solution nearest ``seed``."""
        return self.solve(target, seed).best

    def solve_batch(self, targets: Array, seeds: Array | None = None) -> BatchIKResult:
        """The solution nearest its seed for each of N targets (N, 4, 4), vectorised.

        Analytic arms: the compiled nearest-branch path per target (about 7 us each; without
        it, every branch of every target at once in numpy, then batched Newton polishing); the
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
        if self._fast is not None:  # the compiled nearest-branch path, one target at a time
            rots = np.ascontiguousarray(targets[:, :3, :3])
            poss = np.ascontiguousarray(targets[:, :3, 3])
            refs_c = np.ascontiguousarray(refs)
            for k in range(n):
                fast = self._nearest_compiled(rots[k], poss[k], refs_c[k], None)
                if fast is not None:
                    q_out[k], errs[k], done[k] = fast.q, (fast.position_error,
                                                          fast.orientation_error), True
        elif self.analytic is not None:
            self._batch_analytic(targets, refs, q_out, errs, done)
        for i in np.flatnonzero(~done):
            try:
                sol = self.solve(targets[i], refs[i]).best
            except IKError:
                continue
            q_out[i], errs[i], done[i] = sol.q, (sol.position_error, sol.orientation_error), True
        return BatchIKResult(q_out, done, errs[:, 0], errs[:, 1], time.perf_counter() - start)

    def _batch_analytic(self, targets: Array, refs: Array, q_out: Array, errs: Array,
                        done: NDArray[np.bool_]) -> None:
        assert self.analytic is not None
        if self._poe is None:
            self._poe = PoeChain(self.chain, self.frame)
        rot, pos = targets[:, :3, :3], targets[:, :3, 3]
        branches, valid = self.analytic.solve_batch(rot, pos)          # (N, 8, 6), (N, 8)
        wound = self._wind_batch(branches, refs[:, None, :])
        excess = np.maximum(self.lower - wound, wound - self.upper).max(axis=2)
        dist = np.sum((wound - refs[:, None, :]) ** 2, axis=2)
        dist[~valid | (excess > ANALYTIC_SLACK)] = np.inf
        order = np.argsort(dist, axis=1)
        tol_p, tol_r = self.options.position_tolerance, self.options.orientation_tolerance
        rows = np.arange(len(targets))
        for rank in range(8):
            active = rows[~done & np.isfinite(dist[rows, order[:, rank]])]
            if len(active) == 0:
                break
            q = wound[active, order[active, rank]].copy()
            ok = np.zeros(len(active), dtype=bool)
            pe = re = np.zeros(len(active))
            for _ in range(self.options.newton_steps + 1):
                e, jac = self._poe.pose_errors(q, rot[active], pos[active])
                pe = np.linalg.norm(e[:, :3], axis=1)
                re = np.linalg.norm(e[:, 3:], axis=1)
                ok = (pe < tol_p) & (re < tol_r)
                if ok.all():
                    break
                step = np.zeros_like(q)
                todo = ~ok
                try:
                    step[todo] = np.linalg.solve(jac[todo], e[todo][..., None])[..., 0]
                except np.linalg.LinAlgError:
                    break  # a singular Jacobian in the batch: leave these to solve()
                q = q + step
            q = self._wind_batch(q, refs[active])
            inside = np.all((q >= self.lower - 1e-9) & (q <= self.upper + 1e-9), axis=1)
            good = ok & inside
            idx = active[good]
            q_out[idx] = q[good]
            errs[idx, 0], errs[idx, 1] = pe[good], re[good]
            done[idx] = True

    def _wind_batch(self, q: Array, ref: Array) -> Array:
        """:meth:`_wind` vectorised over any leading dimensions."""
        out = np.array(q, float)
        lo, hi = self.lower, self.upper
        wide = self.wide & self.revolute
        narrow = self.revolute & ~self.wide
        k = np.round((ref - out) / TWO_PI)
        wide_v = out + TWO_PI * k
        wide_v = np.where(wide_v > hi, wide_v - TWO_PI * np.ceil((wide_v - hi) / TWO_PI),
                          wide_v)
        wide_v = np.where(wide_v < lo, wide_v + TWO_PI * np.ceil((lo - wide_v) / TWO_PI),
                          wide_v)
        up = (out < lo) & (out + TWO_PI - hi < lo - out)
        down = (out > hi) & (lo - (out - TWO_PI) < out - hi)
        narrow_v = out + TWO_PI * up - TWO_PI * down
        return np.where(wide, wide_v, np.where(narrow, narrow_v, out))

    # ------------------------------------------------------------------ analytic
    def _solve_analytic(self, rot: Array, pos: Array, ref: Array, all_solutions: bool,
                        collision: CollisionWorld | None
                        ) -> tuple[list[IKSolution], _Violation | None, list[Array]]:
        """Branches in order of distance to ``ref``, expanded lazily: an arm branch's wrist is
        only solved when its (q1, q2, q3) part alone is nearer than the best full candidate, so
        the nearest solution is exact and usually costs one wrist solve."""
        assert self.analytic is not None
        r = rot.tolist()
        refl = ref.tolist()
        arms = []
        for arm in self.analytic.arm_branches(r, pos):
            wound = self._wind_list(list(arm), refl, 0)
            arms.append((_dist(wound, refl, 0, 3), wound, arm))
        arms.sort(key=lambda a: a[0])
        heap: list[tuple[float, int, list[float]]] = []
        counter = 0
        found: list[IKSolution] = []
        violation: _Violation | None = None
        tried: list[Array] = []
        while True:
            while arms and (not heap or arms[0][0] <= heap[0][0]):
                d_arm, wound, arm = arms.pop(0)
                for wrist in self._wrist_candidates(r, arm, refl):
                    q = wound + self._wind_list(list(wrist), refl, 3)
                    heapq.heappush(heap, (d_arm + _dist(q, refl, 3, 6), counter, q))
                    counter += 1
            if not heap:
                break
            _, _, q = heapq.heappop(heap)
            tried.append(np.array(q))
            bad = self._limit_violation(q)
            if bad is not None and bad.excess > ANALYTIC_SLACK:
                if violation is None or bad.excess < violation.excess:
                    violation = bad
                continue  # clearly outside: not worth polishing
            sol = self._polish(np.array(q), rot, pos)
            if sol is None:
                continue
            qq = self._wind(np.array(sol.q), ref)
            bad = self._limit_violation(qq)
            if bad is not None and bad.excess < LIMIT_CLAMP:
                sol = self._clamped(qq, rot, pos) or sol
                qq = np.array(sol.q)
                bad = self._limit_violation(qq)
            if bad is not None:
                if violation is None or bad.excess < violation.excess:
                    violation = bad
                continue
            sol = IKSolution(_frozen(qq), sol.position_error, sol.orientation_error)
            if any(np.max(np.abs(sol.q - f.q)) < self.options.distinct for f in found):
                continue
            if collision is not None and collision.in_collision(sol.q):
                self._collided.append(sol.q)
                continue
            found.append(sol)
            if not all_solutions:
                break
        return found, (violation if not found else None), tried

    def _wrist_candidates(self, r: list[list[float]], arm: tuple[float, float, float],
                          ref: list[float]) -> list[tuple[float, float, float]]:
        """The wrist branches of an arm branch. Near the wrist singularity (q5 ~ 0) only
        q4 + c q6 is fixed by a spherical wrist, and a real wrist (axes a millimetre apart)
        has its exact solutions at particular splits, so several splits are offered: the
        seed's q4, 0, +-pi/2 and pi."""
        assert self.analytic is not None
        out = []
        for q4, q5, q6 in self.analytic.wrist_branches(r, *arm):
            out.append((q4, q5, q6))
            if abs(math.sin(q5)) < WRIST_SINGULAR and abs(math.cos(q5)) > 0.5:
                c = self.analytic.wrist_coupling
                for split in (ref[3], 0.0, math.pi / 2, -math.pi / 2, math.pi):
                    out.append((split, q5, q6 + c * (q4 - split)))
        return out

    def _polish(self, q: Array, rot: Array, pos: Array) -> IKSolution | None:
        """Newton steps on the exact model from an analytic branch."""
        tol_p, tol_r = self.options.position_tolerance, self.options.orientation_tolerance
        target = self.kin.target(rot, pos)
        for _ in range(self.options.newton_steps):
            e, pe, re, jac = self.kin.local_error(q, self.fid, target)
            if pe < tol_p and re < tol_r:
                return IKSolution(q, pe, re)
            _, _, step, info = dgesv(jac, e)
            if info != 0:  # singular: damped least squares instead
                step = jac.T @ dgesv(jac @ jac.T + 1e-6 * np.eye(6), e)[2]
            biggest = float(np.max(np.abs(step)))
            if biggest > MAX_NEWTON_STEP:  # near a singularity: do not jump across the space
                step *= MAX_NEWTON_STEP / biggest
            q = q + step
        return None

    def _clamped(self, q: Array, rot: Array, pos: Array) -> IKSolution | None:
        """A solution with the joints a hair outside their limits held on the limit: Newton
        (least squares) on the other joints, kept if it reaches the tolerance. A joint that a
        step pushes beyond its limit is held there too (an active set), so a target whose
        solution sits in a corner of the limits, several joints on their limits, is reached."""
        stuck = (q < self.lower) | (q > self.upper)
        q = np.clip(q, self.lower, self.upper)
        target = self.kin.target(rot, pos)
        for _ in range(2 * self.options.newton_steps):
            e, pe, re, jac = self.kin.local_error(q, self.fid, target)
            if pe < self.options.position_tolerance and re < self.options.orientation_tolerance:
                return IKSolution(q, pe, re)
            free = ~stuck
            if not free.any():
                return None
            step = np.linalg.lstsq(jac[:, free], e, rcond=None)[0]
            q = q.copy()
            q[free] += step
            out = (q < self.lower - 1e-9) | (q > self.upper + 1e-9)
            if out.any():
                q = np.clip(q, self.lower, self.upper)
                stuck |= out
        return None

    # ------------------------------------------------------------------ numeric
    def _solve_numeric(self, rot: Array, pos: Array, ref: Array, seeded: bool,
                       all_solutions: bool, collision: CollisionWorld | None,
                       start: float, starts: list[Array] | None = None) -> list[IKSolution]:
        """LM from the seed, then from ``starts`` (e.g. analytic branches), then from random
        configurations, until the time budget is spent."""
        found: list[IKSolution] = []
        budget = self.options.time_budget
        queue = [ref if seeded else (self.lower + self.upper) / 2, *(starts or [])]
        attempt = 0
        while time.perf_counter() - start < budget:
            q0 = (np.clip(queue[attempt], self.lower, self.upper) if attempt < len(queue)
                  else self._rng.uniform(self.lower, self.upper))
            attempt += 1
            sol = self._levenberg_marquardt(q0, rot, pos, start + budget)
            if sol is None:
                continue
            qq = self._wind(np.array(sol.q), ref)
            if self._limit_violation(qq) is not None:
                continue
            sol = IKSolution(_frozen(qq), sol.position_error, sol.orientation_error)
            if any(np.max(np.abs(sol.q - f.q)) < self.options.distinct for f in found):
                continue
            if collision is not None and collision.in_collision(sol.q):
                self._collided.append(sol.q)
                continue
            found.append(sol)
            if not all_solutions:
                break
        return found

    def _levenberg_marquardt(self, q: Array, rot: Array, pos: Array, deadline: float,
                             iterations: int = LM_ITERATIONS) -> IKSolution | None:
        """Levenberg-Marquardt from ``q``: damping = LM_DAMPING * squared error + LM_FLOOR
        (large far from the target, vanishing near it), steps capped at MAX_LM_STEP; the
        joints are free during the descent and wound into their limits at the end."""
        tol_p, tol_r = self.options.position_tolerance, self.options.orientation_tolerance
        if self._chain_arrays is not None:  # compiled, on the product of exponentials
            q = np.array(q, dtype=float)
            c = self._chain_arrays
            ok, pe, re = ik_kernel.levenberg_marquardt(
                q, rot, pos, c.axes, c.points, c.revolute, c.tool, tol_p, tol_r, iterations,
                LM_DAMPING, LM_FLOOR, MAX_LM_STEP)
            return IKSolution(q, pe, re) if ok else None
        target = self.kin.target(rot, pos)
        diag = self._diag
        for it in range(iterations):
            e, pe, re, jac = self.kin.local_error(q, self.fid, target)
            if pe < tol_p and re < tol_r:
                return IKSolution(q, pe, re)
            if it % 8 == 7 and time.perf_counter() > deadline:
                return None
            h = jac.T @ jac
            h.flat[diag] += LM_DAMPING * float(e @ e) + LM_FLOOR
            _, _, step, info = dgesv(h, jac.T @ e)
            if info != 0:
                return None
            biggest = float(np.max(np.abs(step)))
            if biggest > MAX_LM_STEP:
                step *= MAX_LM_STEP / biggest
            q = q + step
        return None

    # ------------------------------------------------------------------ limits and windings
    def _wind(self, q: Array, ref: Array) -> Array:
        """Each revolute angle moved by whole turns into its limits, to the winding nearest
        ``ref`` where the range is wider than 2 pi; where neither winding fits (a solution on
        a limit, a hair outside it), the one less outside, for the clamping to finish."""
        return np.array(self._wind_list(list(map(float, q)), list(map(float, ref)), 0))

    def _wind_list(self, q: list[float], ref: list[float], offset: int) -> list[float]:
        """:meth:`_wind` on plain floats for joints ``offset .. offset + len(q)``."""
        for k in range(len(q)):
            i = k + offset
            if not self._rev[i]:
                continue
            v, lo, hi = q[k], self._lo[i], self._hi[i]
            if self._wide[i]:
                v += TWO_PI * round((ref[i] - v) / TWO_PI)
                while v > hi:
                    v -= TWO_PI
                while v < lo:
                    v += TWO_PI
            elif v < lo and v + TWO_PI - hi < lo - v:
                v += TWO_PI  # the other winding is inside, or less outside
            elif v > hi and lo - (v - TWO_PI) < v - hi:
                v -= TWO_PI
            q[k] = v
        return q

    def _limit_violation(self, q: Array | list[float]) -> _Violation | None:
        """The worst limit violation of ``q``, or None."""
        worst = None
        for i in range(len(q)):
            excess = float(max(self._lo[i] - q[i], q[i] - self._hi[i]))
            if excess > 1e-9 and (worst is None or excess > worst.excess):
                worst = _Violation(i, float(q[i]), excess)
        return worst

    # ------------------------------------------------------------------ failures
    def _raise_failure(self, rot: Array, pos: Array, ref: Array,
                       violation: _Violation | None, collision: CollisionWorld | None,
                       start: float) -> None:
        if collision is not None and self._collided:
            distinct: list[Array] = []
            for q in self._collided:
                if not any(np.max(np.abs(q - d)) < self.options.distinct for d in distinct):
                    distinct.append(q)
            n = len(distinct)
            pairs = sorted({p for q in distinct for p in collision.contacts(q)})
            self._collided = []
            raise AllSolutionsInCollisionError(n, pairs)
        if violation is not None:
            i = violation.index
            raise JointLimitError(self.names[i], violation.value, float(self.lower[i]),
                                  float(self.upper[i]))
        distance = self._closest_approach(rot, pos, ref)
        raise UnreachableError(distance, f"no {self.method} solution within "
                               f"{self.options.position_tolerance:g} m / "
                               f"{self.options.orientation_tolerance:g} rad after "
                               f"{time.perf_counter() - start:.3f} s")

    def _closest_approach(self, rot: Array, pos: Array, ref: Array) -> float:
        """How far (m) the frame stays from the target position at best: 4096 random
        configurations (vectorised forward kinematics), the 8 nearest then refined by damped
        least squares on position, inside the limits."""
        if self._poe is None:
            self._poe = PoeChain(self.chain, self.frame)
        samples = self._rng.uniform(self.lower, self.upper, size=(4096, len(self.names)))
        poses, _ = self._poe.model.frame_jacobian(samples, self.frame)
        gaps = np.linalg.norm(poses[:, :3, 3] - pos, axis=1)
        best = math.inf
        starts = [np.clip(ref, self.lower, self.upper), *samples[np.argsort(gaps)[:8]]]
        for q in starts:
            for _ in range(60):
                e, jac = self.kin.pose_error(q, self.fid, rot, pos)
                ep, jp = e[:3], jac[:3]
                gap = float(ep @ ep)
                best = min(best, math.sqrt(gap))
                damping = 1e-4 + 0.1 * gap  # small steps while far, Newton steps when near
                step = jp.T @ np.linalg.solve(jp @ jp.T + damping * np.eye(3), ep)
                q = np.clip(q + step, self.lower, self.upper)
        return min(best, float(gaps.min()))
