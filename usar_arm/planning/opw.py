"""Closed-form IK for ortho-parallel arms with a spherical wrist (the "OPW" class: KUKA KR...).

The structure is read from the robot's own axes at the zero configuration (product of
exponentials: each joint i has a unit axis w_i through a point p_i, and the tool pose is M), not
from a table: joint 1 is perpendicular to joints 2 and 3, which are parallel; joints 4, 5, 6
are successively perpendicular and (nearly) meet at a wrist centre. Then, for a tool target:

1. the wrist centre W follows from the target and the tool's fixed offset from it;
2. q1: the wrist centre's offset along the rotated joint-2 axis is fixed (the lateral offset b)
   -> two solutions;
3. q2, q3: a planar two-link problem in the plane normal to joint 2 -> two solutions each;
4. q4, q5, q6: the remaining rotation, by Paden-Kahan subproblems -> two solutions each.

So up to 8 branches. Where the real arm deviates slightly from the class (the USARSim KR60's
wrist axes miss each other by 2 mm; wire-rounded offsets), every branch is polished by Newton
steps on the exact model afterwards (:mod:`usar_arm.planning.ik`).

Scalar maths on plain floats: this runs per IK query and must cost microseconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning.screw import (
    PARALLEL,
    PERPENDICULAR,
    V,
    closest_point,
    cross,
    dot,
    rodrigues,
    six_axes,
    sub,
    subproblem1,
    v3,
    wrap,
)
from usar_arm.planning.two_link import TwoLink
from usar_arm.urdf.opw_fit import OpwLengths

STRUCTURE = (PERPENDICULAR, PARALLEL, PERPENDICULAR, PERPENDICULAR, PERPENDICULAR)
"""How each joint's axis stands to the next's on an ortho-parallel arm (joints 4 to 6 meet
too: the spherical wrist)."""


class NotOrthoParallel(ValueError):
    """The arm is not in the ortho-parallel/spherical-wrist class; the reason says why."""


@dataclass(frozen=True)
class OpwParameters(OpwLengths):
    """The classical OPW parameters (m) of the arm, for reports and other OPW solvers: the
    seven lengths (:class:`~usar_arm.urdf.opw_fit.OpwLengths`) and the wrist's offset."""

    wrist_offset: float
    """How far (m) the wrist axes miss a common point on the real model (0 for a true OPW arm)."""


class OrthoParallelArm:
    """The closed-form solver of one arm, built from its zero-configuration axes.

    Args:
        axes: (6, 3) unit joint axes at q = 0, base frame.
        points: (6, 3) a point on each axis, base frame (m).
        tool: 4x4 pose of the IK frame at q = 0.
        tolerance: allowed deviation (rad) from perpendicular/parallel and distance (m) of the
            wrist axes from their common point.

    Raises:
        NotOrthoParallel: naming which condition fails.
    """

    def __init__(self, axes: Array, points: Array, tool: Array, tolerance: float = 0.02):
        w, p = six_axes(axes, points, STRUCTURE, tolerance, NotOrthoParallel)
        wrist, miss = closest_point(np.array(w[3:]), np.array(p[3:]))
        if miss > max(tolerance, 0.05):
            raise NotOrthoParallel(f"wrist axes miss a common point by {miss:.4f} m")
        self.w = w
        self.p = p
        self.tool = np.asarray(tool, float)
        self.wrist_offset = miss
        self.slack = 2.0 * miss + 1e-9
        """How far (m) beyond the model's reach a target may be and still get a (clamped)
        branch: the real arm's wrist offset can put it there."""
        self.W0: V = (float(wrist[0]), float(wrist[1]), float(wrist[2]))
        rm, pm = self.tool[:3, :3], self.tool[:3, 3]
        self._rm_t = rm.T
        self._tool_to_wrist = rm.T @ (wrist - pm)  # wrist centre in the tool frame
        self.u: V = w[1]
        self.two_link = TwoLink.of(self.u, w[2], p[1], p[2], self.W0, self.slack)
        """Joints 2 and 3 carrying the wrist centre."""
        self.lateral = dot(self.u, sub(self.W0, p[0]))
        # Constants of the per-query maths.
        self._tw = v3(self._tool_to_wrist)
        self._w1xu = cross(w[0], self.u)
        self._p1_2d = self.two_link.plane(p[0])
        v = cross(w[5], (1.0, 0.0, 0.0))
        if dot(v, v) < 1e-6:
            v = cross(w[5], (0.0, 1.0, 0.0))
        nv = math.sqrt(dot(v, v))
        self._v: V = (v[0] / nv, v[1] / nv, v[2] / nv)
        self._m6 = v3(self._rm_t @ np.array(w[5]))
        self._mv = v3(self._rm_t @ np.array(self._v))
        self._c45 = dot(w[3], w[4])
        self._w5w6 = dot(w[4], w[5])
        self._w4xw5 = cross(w[3], w[4])
        self._cr2 = dot(self._w4xw5, self._w4xw5)
        self.wrist_coupling = 1.0 if dot(w[3], w[5]) > 0 else -1.0
        """At q5 = 0 joints 4 and 6 turn about one line: only q4 + coupling * q6 matters."""

    def parameters(self) -> OpwParameters:
        """The classical OPW parameters, measured from the foot of joint 1's axis.

        At this arm's zero pose the upper arm points along joint 1's axis and the forearm
        across it, so: c1 = height of joint 2, a1 = reach of joint 2 from axis 1, c2 = upper
        arm, c3 = forearm (joint 3 -> wrist centre, across), a2 = -(rise of the wrist centre
        above joint 3), b = lateral offset, c4 = wrist centre -> tool. Approximate when
        ``wrist_offset`` > 0.
        """
        w1, p1, u = self.w[0], self.p[0], self.u
        foot = sub(p1, tuple(dot(w1, p1) * x for x in w1))  # type: ignore[arg-type]
        across = cross(u, w1)
        rel2 = sub(self.p[1], foot)
        fore = sub(self.W0, self.p[2])
        sign = 1.0 if dot(across, sub(self.W0, foot)) >= 0 else -1.0
        return OpwParameters(
            a1=sign * dot(across, rel2), a2=-dot(w1, fore), b=self.lateral,
            c1=dot(w1, rel2), c2=math.sqrt(self.two_link.l2sq), c3=sign * dot(across, fore),
            c4=float(np.linalg.norm(self._tool_to_wrist)), wrist_offset=self.wrist_offset)

    def arm_branches(self, rot: Array | list[list[float]], pos: Array
                     ) -> list[tuple[float, float, float]]:
        """(q1, q2, q3) of every arm branch (up to 4) placing the wrist centre for a tool pose."""
        r = rot.tolist() if isinstance(rot, np.ndarray) else rot
        tw = self._tw
        wx = r[0][0] * tw[0] + r[0][1] * tw[1] + r[0][2] * tw[2] + float(pos[0])
        wy = r[1][0] * tw[0] + r[1][1] * tw[1] + r[1][2] * tw[2] + float(pos[1])
        wz = r[2][0] * tw[0] + r[2][1] * tw[1] + r[2][2] * tw[2] + float(pos[2])
        w1, p1, u = self.w[0], self.p[0], self.u
        d = (wx - p1[0], wy - p1[1], wz - p1[2])
        h = dot(w1, d)
        dh = (d[0] - h * w1[0], d[1] - h * w1[1], d[2] - h * w1[2])
        a = dot(u, dh)
        b = dot(self._w1xu, dh)
        rad = math.hypot(a, b)
        if rad < 1e-12 or abs(self.lateral) > rad + self.slack:
            return []
        base = math.atan2(b, a)
        spread = math.acos(max(-1.0, min(1.0, self.lateral / rad)))
        out: list[tuple[float, float, float]] = []
        two = self.two_link
        for q1 in (base + spread, base - spread):
            back = rodrigues(w1, -q1, d)
            x = dot(two.ea, back) + self._p1_2d[0]
            y = dot(two.eb, back) + self._p1_2d[1]
            out.extend((wrap(q1), wrap(q2), wrap(q3)) for q2, q3 in two.angles(x, y))
        return out

    def wrist_branches(self, rot: Array | list[list[float]], q1: float, q2: float, q3: float
                       ) -> list[tuple[float, float, float]]:
        """(q4, q5, q6) of every wrist branch (up to 2) completing arm branch (q1, q2, q3).

        With R_w = (R1 R2 R3)^T R_target R_M^T, solves Rot(w4,q4) Rot(w5,q5) Rot(w6,q6) = R_w
        using only R_w w6 and R_w v (Paden-Kahan subproblems 2 and 1); R2 R3 is one rotation
        about u by q2 + q3 (joints 2 and 3 are parallel).
        """
        r = rot.tolist() if isinstance(rot, np.ndarray) else rot
        m6, mv = self._m6, self._mv
        t6 = (r[0][0] * m6[0] + r[0][1] * m6[1] + r[0][2] * m6[2],
              r[1][0] * m6[0] + r[1][1] * m6[1] + r[1][2] * m6[2],
              r[2][0] * m6[0] + r[2][1] * m6[1] + r[2][2] * m6[2])
        tv = (r[0][0] * mv[0] + r[0][1] * mv[1] + r[0][2] * mv[2],
              r[1][0] * mv[0] + r[1][1] * mv[1] + r[1][2] * mv[2],
              r[2][0] * mv[0] + r[2][1] * mv[1] + r[2][2] * mv[2])
        theta = q2 + self.two_link.s3 * q3
        w1, u = self.w[0], self.u
        target = rodrigues(u, -theta, rodrigues(w1, -q1, t6))
        rv = rodrigues(u, -theta, rodrigues(w1, -q1, tv))
        w4, w5, w6 = self.w[3], self.w[4], self.w[5]
        c = self._c45
        den = c * c - 1.0
        t4 = dot(w4, target)
        alpha = (c * self._w5w6 - t4) / den
        beta = (c * t4 - self._w5w6) / den
        cr = self._w4xw5
        g2 = (1.0 - alpha * alpha - beta * beta - 2 * alpha * beta * c) / self._cr2
        gammas = (0.0,) if g2 <= 1e-14 else (math.sqrt(g2), -math.sqrt(g2))
        out = []
        for g in gammas:
            z = (alpha * w4[0] + beta * w5[0] + g * cr[0], alpha * w4[1] + beta * w5[1]
                 + g * cr[1], alpha * w4[2] + beta * w5[2] + g * cr[2])
            q5 = subproblem1(w5, w6, z)
            q4 = subproblem1(w4, z, target)
            mv6 = rodrigues(w5, -q5, rodrigues(w4, -q4, rv))
            q6 = subproblem1(w6, self._v, mv6)
            out.append((wrap(q4), wrap(q5), wrap(q6)))
        return out

    def solve(self, rot: Array, pos: Array) -> list[list[float]]:
        """Every branch (up to 8) of joint values (rad, wrapped to (-pi, pi]) for a tool pose."""
        r = rot.tolist()
        return [[*arm, *wrist] for arm in self.arm_branches(r, pos)
                for wrist in self.wrist_branches(r, *arm)]

