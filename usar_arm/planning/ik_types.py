"""The IK solver's options and results (:mod:`.ik`): plain frozen dataclasses, shared by the
public API, the branch bookkeeping (:mod:`.ik_branches`) and the numeric solver
(:mod:`.ik_numeric`). Metres and radians."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from usar_arm.core.spatial import Array

if TYPE_CHECKING:
    from usar_arm.planning.collision import CollisionWorld


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
    """Results of :meth:`.ik.IKSolver.solve_batch`: q (N, n; NaN where failed), success (N,),
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


def frozen(q: Array) -> Array:
    """A read-only float copy of ``q``."""
    out = np.array(q, dtype=float)
    out.setflags(write=False)
    return out


def is_new(q: Array, found: list[Array], distinct: float) -> bool:
    """True when ``q`` differs from every configuration of ``found`` by ``distinct`` (rad or m)
    or more on some joint."""
    return not any(np.max(np.abs(q - f)) < distinct for f in found)


def admit(sol: IKSolution, found: list[IKSolution], distinct: float,
          collision: CollisionWorld | None, collided: list[Array]) -> bool:
    """Append ``sol`` to ``found`` when it is a new solution (:func:`is_new`) and collision-free
    (one in collision goes to ``collided``); True when it was appended."""
    if not is_new(sol.q, [f.q for f in found], distinct):
        return False
    if collision is not None and collision.in_collision(sol.q):
        collided.append(sol.q)
        return False
    found.append(sol)
    return True
