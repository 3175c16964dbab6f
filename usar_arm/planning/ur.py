"""Closed-form IK for arms with three parallel axes (the Universal Robots family: UR3/5/10...).

The structure is read from the robot's own axes at the zero configuration (product of
exponentials: joint i has a unit axis w_i through a point p_i, the tool pose is M), not from a DH
table: joint 1 is perpendicular to joint 2; joints 2, 3 and 4 are parallel (direction u);
joint 5 is perpendicular to joint 4 and joint 6 to joint 5, and axes 5 and 6 meet at a point
p56. Writing R_w = R_target R_M^T = R1 Rot(u, theta) R5 R6 (theta = q2 + q3 + q4 up to the
axes' signs), for a tool target:

1. q1: the point P56 (axes 5 and 6 meet there; fixed in the tool frame) is moved by joints 1-4
   only, and joints 2-4 keep its offset along u: u . R1^T (P56 - p1) = u . (p56 - p1)
   -> two solutions (the shoulder left/right);
2. q5: joints 2-4 keep directions' components along u too: u . R1^T w6' = u . R5 w6, with w6'
   the tool's axis 6 -> two solutions (the wrist up/down);
3. q6: R6^T R5^T u = R_w^T R1 u, Paden-Kahan subproblem 1 about w6; free at the wrist
   singularity (R5^T u parallel to w6: q5 ~ 0 on a UR), where the caller's value is taken;
4. theta from the rest of the rotation (subproblem 1 about u), then q2, q3 as the planar two-link
   problem placing joint 4's point, in the plane normal to u -> two solutions (elbow up/down),
   and q4 = theta - q2 - q3.

So up to 8 branches. Where the real arm deviates slightly from the class, every branch is
polished by Newton steps on the exact model afterwards (:mod:`usar_arm.planning.ik`).

Scalar maths on plain floats: the reference of the compiled :mod:`.ur_kernel`.
"""

from __future__ import annotations

import math

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning.opw import NotOrthoParallel
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
    unit,
    v3,
    wrap,
)
from usar_arm.planning.two_link import TwoLink

Matrix = Array | list[list[float]]
"""A 3x3 matrix as an array or nested lists."""
SINGULAR_WRIST = 1e-8
"""|R5^T u x w6| (~ |sin q5| on a UR) below which q6 counts as free (the wrist singularity) and
takes the caller's value: the rotation then fixes it only to eps / |sin q5|, and that error
moves the position (theta turns p56 about axis 4); 1e-8 balances the two, a few 1e-8 at worst
(Newton finishes)."""
STRUCTURE = (PERPENDICULAR, PARALLEL, PARALLEL, PERPENDICULAR, PERPENDICULAR)
"""How each joint's axis stands to the next's on a three-parallel arm (axes 5 and 6 meet
too)."""


class NotThreeParallel(NotOrthoParallel):
    """The arm does not have the three-parallel-axes structure of a UR; the reason says why."""


def _mat(m: Matrix, v: V) -> V:
    """A 3x3 matrix (nested lists or array) times a 3-vector."""
    return (m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2])


def _mat_t(m: Matrix, v: V) -> V:
    """The transpose of a 3x3 matrix times a 3-vector."""
    return (m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
            m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
            m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2])


class ThreeParallelArm:
    """The closed-form solver of one UR-type arm, built from its zero-configuration axes.

    Args:
        axes: (6, 3) unit joint axes at q = 0, base frame.
        points: (6, 3) a point on each axis, base frame (m).
        tool: 4x4 pose of the IK frame at q = 0 (m).
        tolerance: allowed deviation (rad) from perpendicular/parallel; axes 5 and 6 may miss
            each other by up to max(tolerance, 0.05) m.

    Raises:
        NotThreeParallel: naming which condition fails.
    """

    def __init__(self, axes: Array, points: Array, tool: Array, tolerance: float = 0.02):
        w, p = six_axes(axes, points, STRUCTURE, tolerance, NotThreeParallel)
        meet, miss = closest_point(np.array(w[4:]), np.array(p[4:]))  # (half their gap)
        if 2.0 * miss > max(tolerance, 0.05):
            raise NotThreeParallel(f"axes 5 and 6 miss each other by {2 * miss:.4f} m")
        self.w, self.p = w, p
        self.tool = np.asarray(tool, float)
        self.slack = 2.0 * miss + 1e-9
        """How far (m) beyond the model's reach a target may be and still get a (clamped)
        branch: axes 5 and 6 missing each other on the real arm can put it there."""
        self.p56: V = v3(meet)
        self.rm = [[float(v) for v in row] for row in self.tool[:3, :3]]
        self.t56: V = v3(self.tool[:3, :3].T @ (meet - self.tool[:3, 3]))
        self.m6: V = v3(self.tool[:3, :3].T @ np.array(w[5]))
        u = w[1]
        self.u: V = u
        self.s4 = 1.0 if dot(w[3], u) > 0 else -1.0
        self.w1xu: V = cross(w[0], u)
        self.lateral = dot(u, sub(self.p56, p[0]))
        # q5: (A - D) cos q5 + B sin q5 = k - D, from u . Rot(w5, q5) w6 = k; M = |(A - D, B)|.
        a5 = dot(u, w[5])
        b5 = dot(u, cross(w[4], w[5]))
        d5 = dot(u, w[4]) * dot(w[4], w[5])
        self.mag5 = math.hypot(a5 - d5, b5)
        self.phase5 = math.atan2(b5, a5 - d5)
        m2m1 = self.mag5 ** 2 - 1.0
        self.d5 = 0.0 if abs(d5) < 1e-12 else d5
        self.m2m1 = 0.0 if abs(m2m1) < 1e-12 else m2m1
        """D and M^2 - 1, zero on an arm in the class to 1e-12: then sin(q5 - phase) comes
        from |u x w6'| without cancellation, exact near the wrist singularity."""
        self.x: V = unit(sub(w[4], tuple(dot(w[4], u) * c for c in u)))  # type: ignore[arg-type]
        """A unit vector normal to u (w5's part normal to u): turned to find theta."""
        self.r4: V = sub(self.p56, p[3])
        self.two_link = TwoLink.of(u, w[2], p[1], p[2], p[3], self.slack)
        """Joints 2 and 3 carrying joint 4's point."""

    def shoulder(self, r: Matrix, pos: Array) -> tuple[V, list[float]]:
        """P56 - p1 (m) and the q1 (rad, up to 2) keeping P56's offset along u."""
        w1, u = self.w[0], self.u
        t, p1 = _mat(r, self.t56), self.p[0]
        d = (t[0] + float(pos[0]) - p1[0], t[1] + float(pos[1]) - p1[1],
             t[2] + float(pos[2]) - p1[2])
        h = dot(w1, d)
        dh = (d[0] - h * w1[0], d[1] - h * w1[1], d[2] - h * w1[2])
        a, b = dot(u, dh), dot(self.w1xu, dh)
        rad = math.sqrt(a * a + b * b)
        if rad < 1e-12 or abs(self.lateral) > rad + self.slack:
            return d, []
        base = math.atan2(b, a)
        spread = math.acos(max(-1.0, min(1.0, self.lateral / rad)))
        return d, [base + spread, base - spread]

    def wrist(self, r: Matrix, q1: float, q6_free: float) -> list[tuple[float, float, float]]:
        """(q5, q6, theta) (rad) of each wrist branch (up to 2) for shoulder angle q1; q6 is
        ``q6_free`` at the wrist singularity."""
        w1, w5, w6, u = self.w[0], self.w[4], self.w[5], self.u
        n = rodrigues(w1, -q1, _mat(r, self.m6))
        k = dot(u, n)
        s2 = (n[0] - k * u[0]) ** 2 + (n[1] - k * u[1]) ** 2 + (n[2] - k * u[2]) ** 2
        # M^2 sin^2(q5 - phase) = M^2 - (k - D)^2, with 1 - k^2 = |u x w6'|^2 = s2:
        sin2 = s2 + self.m2m1 + 2.0 * k * self.d5 - self.d5 * self.d5
        if self.mag5 < 1e-12 or sin2 < -2e-9:
            return []
        spread = math.atan2(math.sqrt(max(0.0, sin2)), k - self.d5)
        v = _mat(self.rm, _mat_t(r, rodrigues(w1, q1, u)))  # R_w^T R1 u
        out = []
        for q5 in (self.phase5 + spread, self.phase5 - spread):
            g = rodrigues(w5, -q5, u)
            gw = dot(w6, g)
            gn = (g[0] - gw * w6[0], g[1] - gw * w6[1], g[2] - gw * w6[2])
            q6 = q6_free if dot(gn, gn) < SINGULAR_WRIST ** 2 else subproblem1(w6, v, g)
            turned = rodrigues(w6, -q6, rodrigues(w5, -q5, self.x))
            y = rodrigues(w1, -q1, _mat(r, _mat_t(self.rm, turned)))
            out.append((q5, q6, subproblem1(u, self.x, y)))
        return out

    def elbow(self, d: V, q1: float, theta: float) -> list[tuple[float, float]]:
        """(q2, q3) (rad, up to 2) placing joint 4's point for shoulder q1 and total turn
        theta about u; ``d`` = P56 - p1 (m)."""
        back = rodrigues(self.w[0], -q1, d)
        turned = rodrigues(self.u, theta, self.r4)
        p1 = self.p[0]
        x, y = self.two_link.plane((back[0] - turned[0] + p1[0], back[1] - turned[1] + p1[1],
                                 back[2] - turned[2] + p1[2]))
        return self.two_link.angles(x, y)

    def solve(self, rot: Array, pos: Array, q6_free: float = 0.0) -> list[list[float]]:
        """Every branch (up to 8) of joint values (rad, wrapped to (-pi, pi]) for a tool pose
        (rotation 3x3, position m); ``q6_free`` (rad) is q6 where the wrist is singular."""
        r = rot.tolist()
        d, q1s = self.shoulder(r, pos)
        out = []
        for q1 in q1s:
            for q5, q6, theta in self.wrist(r, q1, q6_free):
                for q2, q3 in self.elbow(d, q1, theta):
                    q4 = self.s4 * (theta - q2 - self.two_link.s3 * q3)
                    out.append([wrap(v) for v in (q1, q2, q3, q4, q5, q6)])
        return out
