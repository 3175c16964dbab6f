"""The IK's numeric solver: Newton polishing of a start (an analytic branch), Newton with joints
held on their limits, Levenberg-Marquardt from the seed and random restarts within a time
budget, batched Newton for many targets, and the closest approach of an unreachable target.

It works on the exact model (Pinocchio, or the compiled product of exponentials of
:mod:`.lm_kernel` where the frame lies on one serial path). Metres and radians.
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np
from scipy.linalg.lapack import dgelsd, dgelsd_lwork, dgesv

from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning import lm_kernel
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ik_branches import MAX_NEWTON_STEP, Violation, Windings
from usar_arm.planning.ik_types import IKOptions, IKSolution, admit, frozen
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.planning.poe import PoeModel

LM_ITERATIONS = 25
"""Iterations of one Levenberg-Marquardt attempt before a random restart."""
LM_DAMPING = 0.01
LM_FLOOR = 1e-4
MAX_LM_STEP = 0.5
"""rad or m: the largest joint change of one LM step."""
STALL_STEPS = 3
STALL_RATIO = 0.999
"""A clamped Newton search ends once its squared error has stayed above STALL_RATIO times the
smallest so far for STALL_STEPS steps in a row: held on a limit the target lies beyond, it
settles on a least-squares residual (every failed search on random KR60 poses did within three
steps, then ran its remaining dozen steps at the same error)."""
_LWORK: dict[tuple[int, int], tuple[int, int]] = {}


def _lstsq(a: Array, b: Array) -> Array:
    """The minimum-norm least-squares x of a x = b (a: m x n, m >= n): LAPACK's dgelsd, with
    numpy's ``lstsq(rcond=None)`` cut-off (eps * max(m, n)), without its Python wrapping (a
    third of the time on a 6 x 5 system)."""
    m, n = a.shape
    if (m, n) not in _LWORK:
        work, iwork, _ = dgelsd_lwork(m, n, 1, -1.0)
        _LWORK[(m, n)] = (int(work), int(iwork))
    lwork, iwork = _LWORK[(m, n)]
    x, _, _, info = dgelsd(a, b, lwork, iwork, np.finfo(float).eps * max(m, n))
    if info != 0:
        return np.asarray(np.linalg.lstsq(a, b, rcond=None)[0])
    return np.asarray(x[:n])


class _ChainArrays(NamedTuple):
    """The serial chain as the compiled kernels take it (:mod:`.ik_kernel`): joint axes and
    points at zero (n, 3), 1.0 for revolute joints, the frame's pose at zero (4, 4)."""

    axes: Array
    points: Array
    revolute: Array
    tool: Array


class NumericIK:
    """Newton and Levenberg-Marquardt IK of one frame of one arm.

    Args:
        chain: the robot description. kinematics: its Pinocchio model.
        frame: the solved link. windings: the chain's limits. options: tolerances, budget.
    """

    def __init__(self, chain: KinematicChain, kinematics: KinematicModel, frame: str,
                 windings: Windings, options: IKOptions):
        self.chain = chain
        self.kin = kinematics
        self.frame = frame
        self.fid = kinematics.frame_id(frame)
        self.windings = windings
        self.options = options
        self.lower, self.upper = windings.lower, windings.upper
        self._diag = np.arange(len(self.lower)) * (len(self.lower) + 1)
        self._rng = np.random.default_rng(options.seed)
        self._poe: PoeModel | None = None
        self._chain_arrays: _ChainArrays | None = None
        try:
            poe = PoeModel(chain)
            if poe.joints_moving(frame) == poe.dof:
                self._chain_arrays = _ChainArrays(
                    poe.axes, poe.points, poe.revolute.astype(float),
                    np.ascontiguousarray(chain.frame_pose(frame, np.zeros(chain.dof))))
        except ValueError:  # not one serial path to the frame: Pinocchio's LM only
            pass

    def reseed(self, seed: int) -> None:
        """Restart the random restarts from ``seed``."""
        self._rng = np.random.default_rng(seed)

    @property
    def poe(self) -> PoeModel:
        """The chain's product of exponentials (built on first use)."""
        if self._poe is None:
            self._poe = PoeModel(self.chain)
        return self._poe

    def polish(self, q: Array, rot: Array, pos: Array) -> IKSolution | None:
        """Newton steps on the exact model from ``q`` (an analytic branch)."""
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

    def clamped(self, q: Array, rot: Array, pos: Array) -> IKSolution | None:
        """A solution from ``q`` with the joints held on the limits they would cross: Newton
        (least squares) steps from ``q`` clipped into its limits, kept if it reaches the
        tolerance. Each step holds the joints that sit on a limit and would be pushed beyond
        it (an active set, chosen again at every step, so a joint the closed form put far
        outside is released once the others take its share), and clips the joints a step
        takes across a limit onto it; a target whose solution sits in a corner of the limits,
        several joints on their limits, is reached. A revolute joint outside its limits first
        takes the winding less outside them (a range just short of a turn: the solution on one
        limit is a step beyond the other)."""
        q = np.clip(self.windings.wind(q, q), self.lower, self.upper)
        target = self.kin.target(rot, pos)
        best, stalled = math.inf, 0
        for _ in range(2 * self.options.newton_steps):
            e, pe, re, jac = self.kin.local_error(q, self.fid, target)
            if pe < self.options.position_tolerance and re < self.options.orientation_tolerance:
                return IKSolution(q, pe, re)
            size = float(e @ e)
            stalled = stalled + 1 if size > STALL_RATIO * best else 0
            if stalled >= STALL_STEPS:
                return None  # settled on a least-squares residual: the target needs a joint
            best = min(best, size)  # beyond the limit it is held on
            step = self._held_step(q, e, jac)
            if step is None:
                return None
            q = np.clip(self.windings.wind(q + step, q + step), self.lower, self.upper)
        return None

    def _held_step(self, q: Array, e: Array, jac: Array) -> Array | None:
        """The least-squares step of the joints not held on a limit (None: all are held)."""
        on_lower, on_upper = q <= self.lower + 1e-12, q >= self.upper - 1e-12
        free = np.ones(len(q), dtype=bool)
        while free.any():
            step = np.zeros(len(q))
            step[free] = _lstsq(jac[:, free], e)
            pushed = free & ((on_lower & (step < 0)) | (on_upper & (step > 0)))
            if not pushed.any():
                return step
            free &= ~pushed
        return None

    def search(self, rot: Array, pos: Array, ref: Array, seeded: bool, all_solutions: bool,
               collision: CollisionWorld | None, start: float, starts: list[Array],
               collided: list[Array]) -> list[IKSolution]:
        """LM from the seed, then from ``starts`` (e.g. analytic branches), then from random
        configurations, until the time budget (from ``start``, perf_counter s) is spent.
        Solutions in collision are appended to ``collided``."""
        found: list[IKSolution] = []
        budget = self.options.time_budget
        queue = [ref if seeded else (self.lower + self.upper) / 2, *starts]
        attempt = 0
        while time.perf_counter() - start < budget:
            q0 = (np.clip(queue[attempt], self.lower, self.upper) if attempt < len(queue)
                  else self._rng.uniform(self.lower, self.upper))
            attempt += 1
            sol = self.levenberg_marquardt(q0, rot, pos, start + budget)
            if sol is not None and self.keep(sol, ref, found, all_solutions, collision,
                                             collided):
                break
        return found

    def settle(self, sol: IKSolution, ref: Array, rot: Array | None = None,
               pos: Array | None = None, clamp: float = 0.0
               ) -> tuple[IKSolution | None, Violation | None]:
        """``sol`` wound nearest ``ref``; when it is less than ``clamp`` (rad or m) outside a
        limit, held on the limits it crosses, reaching the target ``rot``, ``pos`` with the
        other joints (:meth:`clamped`). Returns (the solution, None) when it is inside the
        limits, else (None, how far out)."""
        qq = self.windings.wind(np.array(sol.q), ref)
        bad = self.windings.violation(qq)
        if bad is not None and bad.excess < clamp and rot is not None and pos is not None:
            sol = self.clamped(qq, rot, pos) or sol
            qq = np.array(sol.q)
            bad = self.windings.violation(qq)
        if bad is not None:
            return None, bad
        return IKSolution(frozen(qq), sol.position_error, sol.orientation_error), None

    def keep(self, sol: IKSolution, ref: Array, found: list[IKSolution], all_solutions: bool,
             collision: CollisionWorld | None, collided: list[Array]) -> bool:
        """Append ``sol``, wound nearest ``ref``, to ``found`` when it is inside the limits,
        new and (with ``collision``) free; True when the search is done (one was kept and not
        every solution is wanted)."""
        kept, _ = self.settle(sol, ref)
        return kept is not None and admit(kept, found, self.options.distinct, collision,
                                          collided) and not all_solutions

    def levenberg_marquardt(self, q: Array, rot: Array, pos: Array, deadline: float,
                            iterations: int = LM_ITERATIONS) -> IKSolution | None:
        """Levenberg-Marquardt from ``q``: damping = LM_DAMPING * squared error + LM_FLOOR
        (large far from the target, vanishing near it), steps capped at MAX_LM_STEP; the
        joints are free during the descent and wound into their limits at the end."""
        tol_p, tol_r = self.options.position_tolerance, self.options.orientation_tolerance
        if self._chain_arrays is not None:  # compiled, on the product of exponentials
            q = np.array(q, dtype=float)
            c = self._chain_arrays
            ok, pe, re = lm_kernel.levenberg_marquardt(
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

    def closest_approach(self, rot: Array, pos: Array, ref: Array) -> float:
        """How far (m) the frame stays from the target position at best: 4096 random
        configurations (vectorised forward kinematics), the 8 nearest then refined by damped
        least squares on position, inside the limits."""
        samples = self._rng.uniform(self.lower, self.upper, size=(4096, len(self.lower)))
        poses, _ = self.poe.frame_jacobian(samples, self.frame)
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
