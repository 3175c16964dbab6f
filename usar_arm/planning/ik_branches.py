"""The IK's branch bookkeeping: joint windings into the limits, limit violations, and the
closed-form branches of an arm in order of distance to a seed: an ortho-parallel arm with a
spherical wrist (:mod:`.opw`) or an arm with three parallel axes like the UR family (:mod:`.ur`).

:class:`Windings` moves revolute angles by whole turns into their limits (the turn nearest the
seed where a range is wider than 2 pi); :class:`AnalyticBranches` enumerates an arm's branches
nearest first (an OPW arm's lazily) and holds the arrays of its compiled path
(:func:`.ik_kernel.nearest`, :func:`.ur_kernel.nearest`). Neither polishes a solution: that is
:mod:`.ik_numeric`'s job. Radians and metres.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning import ik_kernel, ur_kernel
from usar_arm.planning.ik_types import IKOptions
from usar_arm.planning.opw import NotOrthoParallel, OrthoParallelArm
from usar_arm.planning.poe import PoeModel
from usar_arm.planning.ur import NotThreeParallel, ThreeParallelArm

TWO_PI = 2.0 * math.pi
WRIST_SINGULAR = 0.05
"""|sin q5| below which the wrist is treated as (nearly) singular."""
MAX_NEWTON_STEP = 0.3
"""rad or m: the largest joint change of one polishing step."""
ANALYTIC_SLACK = 0.05
"""rad: an analytic branch this close outside a limit is still polished (the closed form is only
approximate on the real arm, so the exact solution may lie inside)."""


def squared_distance(q: list[float], ref: list[float], start: int, stop: int) -> float:
    """Squared distance (rad^2) of joints start..stop (q holds joints from 0 or from start)."""
    off = 0 if len(q) == stop else start
    return sum((q[i - off] - ref[i]) ** 2 for i in range(start, stop))


@dataclass(frozen=True)
class Violation:
    """Joint ``index`` at ``value`` (rad or m) lies ``excess`` (rad or m) beyond its limits."""

    index: int
    value: float
    excess: float


class Windings:
    """The joint limits of a chain (rad or m) and the windings of its revolute joints."""

    def __init__(self, chain: KinematicChain):
        self.lower = chain.lower()
        self.upper = chain.upper()
        self.wide: NDArray[np.bool_] = (self.upper - self.lower) > TWO_PI + 1e-9
        self.revolute: NDArray[np.bool_] = np.array(
            [j.type.value == "revolute" for j in chain.actuated_joints], dtype=bool)
        self._lo = [float(v) for v in self.lower]
        self._hi = [float(v) for v in self.upper]
        self._rev = [bool(v) for v in self.revolute]
        self._wide = [bool(v) for v in self.wide]

    def wind(self, q: Array, ref: Array) -> Array:
        """Each revolute angle moved by whole turns into its limits, to the winding nearest
        ``ref`` where the range is wider than 2 pi; where neither winding fits (a solution on
        a limit, a hair outside it), the one less outside, for the clamping to finish."""
        return np.array(self.wind_list(list(map(float, q)), list(map(float, ref)), 0))

    def wind_list(self, q: list[float], ref: list[float], offset: int) -> list[float]:
        """:meth:`wind` on plain floats for joints ``offset .. offset + len(q)`` (in place)."""
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

    def violation(self, q: Array | list[float]) -> Violation | None:
        """The worst limit violation of ``q``, or None."""
        worst = None
        for i in range(len(q)):
            excess = float(max(self._lo[i] - q[i], q[i] - self._hi[i]))
            if excess > 1e-9 and (worst is None or excess > worst.excess):
                worst = Violation(i, float(q[i]), excess)
        return worst


class AnalyticArrays(NamedTuple):
    """What :func:`.ik_kernel.nearest` takes besides the query."""

    constants: Array
    lower: Array
    upper: Array
    revolute: Array
    wide: Array
    axes: Array
    points: Array
    tool: Array


class AnalyticBranches:
    """The closed-form branches of an ortho-parallel arm with a spherical wrist (``kind``
    ``opw``), else of an arm with three parallel axes (``kind`` ``ur``).

    Raises:
        NotOrthoParallel: the arm is in neither class (with the reasons).
    """

    def __init__(self, chain: KinematicChain, frame: str, windings: Windings):
        if not all(windings.revolute) or len(chain.joint_names) != 6:
            raise NotOrthoParallel("needs exactly 6 revolute joints")
        zero = np.zeros(chain.dof)
        frames = [(j, f) for j, f in chain.joint_frames(zero) if j.actuated]
        axes = np.array([f[:3, :3] @ np.asarray(j.axis) for j, f in frames])
        points = np.array([f[:3, 3] for _, f in frames])
        tool = np.ascontiguousarray(chain.frame_pose(frame, zero))
        self.arm: OrthoParallelArm | None = None
        self.ur: ThreeParallelArm | None = None
        try:
            self.arm = OrthoParallelArm(axes, points, tool)
            constants = ik_kernel.pack(self.arm)
        except NotOrthoParallel as opw:
            try:
                self.ur = ThreeParallelArm(axes, points, tool)
            except NotThreeParallel as ur:
                raise NotOrthoParallel(f"not ortho-parallel ({opw}) nor three-parallel ({ur})"
                                       ) from None
            constants = ur_kernel.pack(self.ur)
        self.kind = "opw" if self.arm is not None else "ur"
        """Which closed form: ``opw`` or ``ur``."""
        self.windings = windings
        poe = PoeModel(chain)
        self.arrays = AnalyticArrays(
            constants, windings.lower, windings.upper,
            windings.revolute.astype(float), windings.wide.astype(float), poe.axes, poe.points,
            tool)

    def nearest_compiled(self, rot: Array, pos: Array, ref: Array, options: IKOptions
                         ) -> tuple[Array, float, float] | None:
        """The nearest branch, polished, by the compiled path: (q, position error m,
        orientation error rad), or None when the Python path must decide (a singular wrist, a
        limit, no branch)."""
        q = np.empty(len(ref))
        a = self.arrays
        if not ref.flags.writeable:  # (a frozen seed, as a solution's q: read-only arrays are
            ref = ref.copy()  # a type of their own to numba, which the warm-up does not compile)
        if self.ur is not None:
            status, pe, re = ur_kernel.nearest(
                rot, pos, ref, a.constants, a.lower, a.upper, a.revolute, a.wide, a.axes,
                a.points, a.tool, options.position_tolerance, options.orientation_tolerance,
                options.newton_steps, MAX_NEWTON_STEP, ANALYTIC_SLACK, q)
        else:
            status, pe, re = ik_kernel.nearest(
                rot, pos, ref, a.constants, a.lower, a.upper, a.revolute, a.wide, a.axes,
                a.points, a.tool, options.position_tolerance, options.orientation_tolerance,
                options.newton_steps, MAX_NEWTON_STEP, ANALYTIC_SLACK, WRIST_SINGULAR, q)
        return (q, pe, re) if status == ik_kernel.SOLVED else None

    def _ordered_ur(self, rot: Array, pos: Array, ref: Array) -> Iterator[list[float]]:
        """Every branch of a three-parallel arm (wound into the limits; q6 the seed's where
        the wrist is singular), nearest ``ref`` first."""
        cand = np.empty((8, 6))
        count = ur_kernel.branches_free(rot, pos, self.arrays.constants, float(ref[5]), cand)
        refl = ref.tolist()
        wound = [self.windings.wind_list(row, refl, 0) for row in cand[:count].tolist()]
        wound.sort(key=lambda q: squared_distance(q, refl, 0, 6))
        yield from wound

    def ordered(self, rot: Array, pos: Array, ref: Array) -> Iterator[list[float]]:
        """Every branch (wound into the limits), in order of distance to ``ref``, expanded
        lazily: an arm branch's wrist is only solved when its (q1, q2, q3) part alone is nearer
        than the best full candidate, so the first is exact and usually costs one wrist solve
        (a three-parallel arm's eight branches cost 2 us: all are computed)."""
        if self.arm is None:
            yield from self._ordered_ur(rot, pos, ref)
            return
        r = rot.tolist()
        refl = ref.tolist()
        wind = self.windings.wind_list
        arms = []
        for arm in self.arm.arm_branches(r, pos):
            wound = wind(list(arm), refl, 0)
            arms.append((squared_distance(wound, refl, 0, 3), wound, arm))
        arms.sort(key=lambda a: a[0])
        heap: list[tuple[float, int, list[float]]] = []
        counter = 0
        while True:
            while arms and (not heap or arms[0][0] <= heap[0][0]):
                d_arm, wound, arm = arms.pop(0)
                for wrist in self.wrist_candidates(r, arm, refl):
                    q = wound + wind(list(wrist), refl, 3)
                    heapq.heappush(heap, (d_arm + squared_distance(q, refl, 3, 6), counter, q))
                    counter += 1
            if not heap:
                return
            yield heapq.heappop(heap)[2]

    def wrist_candidates(self, r: list[list[float]], arm: tuple[float, float, float],
                         ref: list[float]) -> list[tuple[float, float, float]]:
        """The wrist branches of an arm branch. Near the wrist singularity (q5 ~ 0) only
        q4 + c q6 is fixed by a spherical wrist, and a real wrist (axes a millimetre apart)
        has its exact solutions at particular splits, so several splits are offered: the
        seed's q4, 0, +-pi/2 and pi."""
        assert self.arm is not None
        out = []
        for q4, q5, q6 in self.arm.wrist_branches(r, *arm):
            out.append((q4, q5, q6))
            if abs(math.sin(q5)) < WRIST_SINGULAR and abs(math.cos(q5)) > 0.5:
                c = self.arm.wrist_coupling
                for split in (ref[3], 0.0, math.pi / 2, -math.pi / 2, math.pi):
                    out.append((split, q5, q6 + c * (q4 - split)))
        return out

