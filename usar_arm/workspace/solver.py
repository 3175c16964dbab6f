"""Every IK solution of a batch of tool poses, compiled (:mod:`.kernels`), from a chain.

:class:`AllSolutions` picks the closed form when the arm is ortho-parallel (the same test as
:class:`usar_arm.planning.ik.IKSolver`) and Levenberg-Marquardt from fixed seeds otherwise; it is
deterministic for a given chain, options and seed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning import ik_kernel
from usar_arm.planning.ik import IKOptions, IKSolver
from usar_arm.planning.poe import PoeModel
from usar_arm.workspace import kernels

NUMERIC_SEEDS = 12
"""Seeds of the numeric search per target (the middle of the limits and 11 seeded draws)."""
NUMERIC_ITERATIONS = 40
ANALYTIC_SLACK = 0.05
"""rad: a branch this close outside a limit is still polished (the closed form is approximate
on the learnt arm)."""
MAX_NEWTON_STEP = 0.3


@dataclass(frozen=True)
class Candidates:
    """Solutions of M targets: q (M, K, n; rows beyond ``count`` unused), count (M,),
    manipulability and margin (M, K; rad or m)."""

    q: Array
    count: NDArray[np.int64]
    manipulability: Array
    margin: Array

    @property
    def valid(self) -> NDArray[np.bool_]:
        """(M, K): which rows hold a solution."""
        return np.arange(self.q.shape[1])[None, :] < self.count[:, None]


class AllSolutions:
    """All IK solutions of tool0 (or ``frame``) for batches of poses.

    Args:
        chain: the description; ik: an IK solver of the same chain (for its closed form).
        options: tolerances (m, rad) and the seed of the numeric search's draws.
        distinct: rad or m; solutions closer than this on every joint are one solution.
    """

    def __init__(self, chain: KinematicChain, ik: IKSolver, frame: str = "tool0",
                 options: IKOptions | None = None, distinct: float = 1e-3):
        self.options = options or ik.options
        self.distinct = float(distinct)
        self.lower = np.ascontiguousarray(chain.lower(), float)
        self.upper = np.ascontiguousarray(chain.upper(), float)
        self.middle = (self.lower + self.upper) / 2.0
        poe = PoeModel(chain)
        self.revolute = poe.revolute.astype(float)
        self.wide = ((self.upper - self.lower) > 2 * np.pi + 1e-9).astype(float)
        self.axes = np.ascontiguousarray(poe.axes)
        self.points = np.ascontiguousarray(poe.points)
        self.tool = np.ascontiguousarray(chain.frame_pose(chain.frames.get(frame, frame),
                                                          np.zeros(chain.dof)))
        self.constants = ik_kernel.pack(ik.analytic) if ik.analytic is not None else None
        rng = np.random.default_rng(self.options.seed)
        draws = rng.uniform(self.lower, self.upper, size=(NUMERIC_SEEDS - 1, chain.dof))
        self.seeds = np.ascontiguousarray(np.vstack([self.middle, draws]))

    @property
    def method(self) -> str:
        """``analytic`` (every closed-form branch, polished) or ``numeric``."""
        return "analytic" if self.constants is not None else "numeric"

    @property
    def dof(self) -> int:
        """Number of joints."""
        return int(self.lower.shape[0])

    def manipulability(self, qs: Array) -> Array:
        """Yoshikawa's manipulability of tool0 at configurations (N, n)."""
        return np.asarray(kernels.manipulabilities(np.ascontiguousarray(qs, float).reshape(
            -1, self.dof), self.axes, self.points, self.revolute, self.tool))

    def solve(self, rots: Array, poss: Array) -> Candidates:
        """Every solution of M targets given as rotations (M, 3, 3) and positions (M, 3)."""
        rots = np.ascontiguousarray(rots, float).reshape(-1, 3, 3)
        poss = np.ascontiguousarray(poss, float).reshape(-1, 3)
        m, k = len(rots), kernels.MAX_SOLUTIONS
        q = np.zeros((m, k, self.dof))
        count = np.zeros(m, np.int64)
        manip = np.zeros((m, k))
        room = np.zeros((m, k))
        o = self.options
        if self.constants is not None:
            kernels.analytic_solutions(
                rots, poss, self.constants, self.lower, self.upper, self.revolute, self.wide,
                self.middle, self.axes, self.points, self.tool, o.position_tolerance,
                o.orientation_tolerance, o.newton_steps, MAX_NEWTON_STEP, ANALYTIC_SLACK,
                self.distinct, q, count, manip, room)
        else:
            kernels.numeric_solutions(
                rots, poss, self.seeds, self.lower, self.upper, self.revolute, self.wide,
                self.middle, self.axes, self.points, self.tool, o.position_tolerance,
                o.orientation_tolerance, NUMERIC_ITERATIONS, 0.01, 1e-4, 0.5, self.distinct,
                q, count, manip, room)
        return Candidates(q, count, manip, room)

