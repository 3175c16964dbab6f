"""The elbow both closed forms share: a planar two-link problem (joints 2 and 3 parallel).

An ortho-parallel arm (:mod:`.opw`) and an arm with three parallel axes (:mod:`.ur`) both end
their position problem the same way: in the plane normal to the common direction u of joints 2
and 3, joint 2's point p2 and joint 3's point p3 carry a point E (the wrist centre of an OPW
arm, joint 4's point of a UR) to a target. With c = p3 - p2 and e = E - p3 at q = 0 (2-D, in
the plane's basis ea, eb) and d the target's offset from p2, the law of cosines gives

    c . R(t3) e = (|d|^2 - |c|^2 - |e|^2) / 2  ->  t3 = phase +- acos(rhs / |(K, J)|)

(K = c . e, J = c x e, two solutions: elbow up/down), then q2 turns c + R(t3) e onto d, and
q3 = s3 t3 with s3 the sign of joint 3's axis along u. A target slightly beyond the reach (by
``slack`` m times the reach: the real arm's offsets can put it there) is clamped to the
stretched elbow; Newton steps finish it.

:class:`TwoLink` holds the constants and solves in plain floats (the reference);
:func:`elbow` is the same maths compiled, reading the constants from the kernels' float vector
at an offset (the block :meth:`TwoLink.packed` writes, indices below). Radians and metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning.jit import kernel
from usar_arm.planning.screw import V, dot, plane_basis

EA, EB, P2, P3P2, E, L2SQ, L3SQ, MAG, PHASE, REACH, SLACK, S3 = (
    0, 3, 6, 8, 10, 12, 13, 14, 15, 16, 17, 18)
"""Offsets in the block :meth:`TwoLink.packed` writes: the plane basis ea, eb (3 each), the 2-D
p2, p3 - p2 and e (2 each), then the scalars |c|^2, |e|^2, |(K, J)|, phase (rad), the reach
(m), the slack (m) and s3."""
SIZE = 19
"""How many floats the block takes."""

Point2 = tuple[float, float]
"""A point or vector in the plane's basis (m)."""


@dataclass(frozen=True)
class TwoLink:
    """The planar two-link problem of joints 2 and 3 (see the module).

    Attributes:
        ea: the plane's first basis vector (unit, base frame), with ea x eb = u.
        eb: the plane's second basis vector (unit, base frame).
        p2: joint 2's point in the plane (m).
        p3p2: c = p3 - p2 in the plane (m): the upper arm.
        e: E - p3 in the plane at q = 0 (m): the forearm.
        l2sq: |c|^2 (m^2).
        l3sq: |e|^2 (m^2).
        mag: |(K, J)| with K = c . e, J = c x e (m^2).
        phase: atan2(J, K) (rad).
        reach: sqrt(|c|^2 + |e|^2) (m).
        slack: how far (m, per metre of reach) beyond the reach a target is still clamped.
        s3: the sign (+-1) of joint 3's axis along u: q3 = s3 t3.
    """

    ea: V
    eb: V
    p2: Point2
    p3p2: Point2
    e: Point2
    l2sq: float
    l3sq: float
    mag: float
    phase: float
    reach: float
    slack: float
    s3: float

    @classmethod
    def of(cls, u: V, w3: V, p2: V, p3: V, end: V, slack: float) -> TwoLink:
        """The problem of unit direction ``u`` (joint 2's axis), joint 3's axis ``w3``, the
        joints' points ``p2``, ``p3`` and the carried point ``end`` at q = 0 (base frame, m),
        clamping targets up to ``slack`` (m per metre of reach) beyond the reach."""
        ea, eb = plane_basis(u)
        a2, a3, a4 = (dot(ea, p2), dot(eb, p2)), (dot(ea, p3), dot(eb, p3)), (dot(ea, end),
                                                                            dot(eb, end))
        c = (a3[0] - a2[0], a3[1] - a2[1])
        e = (a4[0] - a3[0], a4[1] - a3[1])
        l2sq, l3sq = c[0] ** 2 + c[1] ** 2, e[0] ** 2 + e[1] ** 2
        k, j = c[0] * e[0] + c[1] * e[1], -c[0] * e[1] + c[1] * e[0]
        return cls(ea=ea, eb=eb, p2=a2, p3p2=c, e=e, l2sq=l2sq, l3sq=l3sq,
                   mag=math.hypot(k, j), phase=math.atan2(j, k),
                   reach=math.sqrt(l2sq + l3sq), slack=slack,
                   s3=1.0 if dot(w3, u) > 0 else -1.0)

    def plane(self, x: V) -> Point2:
        """A base-frame point (m) in the plane's basis (m)."""
        return (dot(self.ea, x), dot(self.eb, x))

    def angles(self, x: float, y: float) -> list[tuple[float, float]]:
        """(q2, q3) (rad, not wrapped; up to 2: elbow up, then down) carrying E to the plane
        point (x, y) (m); none beyond the reach and its slack."""
        dx, dy = x - self.p2[0], y - self.p2[1]
        rhs = (dx * dx + dy * dy - self.l2sq - self.l3sq) / 2.0
        if self.mag < 1e-12 or abs(rhs) > self.mag + self.slack * self.reach:
            return []  # beyond the reach (slightly beyond: clamped, Newton finishes it)
        delta = math.acos(max(-1.0, min(1.0, rhs / self.mag)))
        out = []
        for t3 in (self.phase + delta, self.phase - delta):
            c3, s3 = math.cos(t3), math.sin(t3)
            ex = self.p3p2[0] + c3 * self.e[0] - s3 * self.e[1]
            ey = self.p3p2[1] + s3 * self.e[0] + c3 * self.e[1]
            q2 = math.atan2(ex * dy - ey * dx, ex * dx + ey * dy)
            out.append((q2, self.s3 * t3))
        return out

    def packed(self) -> Array:
        """The constants as the block :func:`elbow` reads (``SIZE`` floats, offsets above)."""
        block = np.zeros(SIZE)
        for offset, value in ((EA, self.ea), (EB, self.eb), (P2, self.p2),
                              (P3P2, self.p3p2), (E, self.e)):
            block[offset:offset + len(value)] = value
        block[L2SQ:] = (self.l2sq, self.l3sq, self.mag, self.phase, self.reach, self.slack,
                        self.s3)
        return block


@kernel
def elbow(c: Array, at: int, x: float, y: float, out: Array) -> int:
    """:meth:`TwoLink.angles` compiled, the constants the block at ``c[at:at+SIZE]``: (q2, q3)
    (rad) into the rows of ``out`` (2, 2); returns how many (0 or 2)."""
    dx, dy = x - c[at + P2], y - c[at + P2 + 1]
    mag = c[at + MAG]
    rhs = (dx * dx + dy * dy - c[at + L2SQ] - c[at + L3SQ]) / 2.0
    if mag < 1e-12 or abs(rhs) > mag + c[at + SLACK] * c[at + REACH]:
        return 0
    delta = math.acos(max(-1.0, min(1.0, rhs / mag)))
    for k in range(2):
        t3 = c[at + PHASE] + (1.0 if k == 0 else -1.0) * delta
        c3, s3 = math.cos(t3), math.sin(t3)
        ex = c[at + P3P2] + c3 * c[at + E] - s3 * c[at + E + 1]
        ey = c[at + P3P2 + 1] + s3 * c[at + E] + c3 * c[at + E + 1]
        out[k, 0] = math.atan2(ex * dy - ey * dx, ex * dx + ey * dy)
        out[k, 1] = c[at + S3] * t3
    return 2
