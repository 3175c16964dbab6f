"""The scalar geometry the closed-form IK solvers share (:mod:`.opw`, :mod:`.ur`): 3-vectors as
tuples of floats, Rodrigues' rotation, Paden-Kahan subproblem 1, the point nearest several
axes, and an arm's six zero-configuration axes read and checked against a structure.

Plain floats, not arrays: the solvers run per IK query and must cost microseconds (their
compiled twins are :mod:`.ik_kernel` and :mod:`.ur_kernel`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from usar_arm.core.spatial import Array

V = tuple[float, float, float]
"""A 3-vector (m, or unitless for a direction)."""
TWO_PI = 2.0 * math.pi


def v3(x: Array | Sequence[float]) -> V:
    """A 3-vector as a tuple of floats."""
    return (float(x[0]), float(x[1]), float(x[2]))


def dot(a: V, b: V) -> float:
    """The dot product of two 3-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: V, b: V) -> V:
    """The cross product a x b."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def sub(a: V, b: V) -> V:
    """The difference a - b."""
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def unit(x: V) -> V:
    """``x`` divided by its length (``x`` must not be zero)."""
    n = math.sqrt(dot(x, x))
    return (x[0] / n, x[1] / n, x[2] / n)


def rodrigues(w: V, angle: float, v: V) -> V:
    """Rodrigues: ``v`` rotated by ``angle`` (rad) about the unit axis ``w``."""
    c, s = math.cos(angle), math.sin(angle)
    k = dot(w, v) * (1.0 - c)
    x = cross(w, v)
    return (v[0] * c + x[0] * s + w[0] * k, v[1] * c + x[1] * s + w[1] * k,
            v[2] * c + x[2] * s + w[2] * k)


def subproblem1(w: V, p: V, q: V) -> float:
    """Paden-Kahan subproblem 1: the angle (rad) about unit axis ``w`` taking ``p`` to ``q``."""
    pw, qw = dot(w, p), dot(w, q)
    pp = (p[0] - w[0] * pw, p[1] - w[1] * pw, p[2] - w[2] * pw)
    qq = (q[0] - w[0] * qw, q[1] - w[1] * qw, q[2] - w[2] * qw)
    return math.atan2(dot(w, cross(pp, qq)), dot(pp, qq))


def wrap(angle: float) -> float:
    """``angle`` (rad) wrapped into [-pi, pi)."""
    return (angle + math.pi) % TWO_PI - math.pi


def plane_basis(u: V) -> tuple[V, V]:
    """Two unit vectors ``ea``, ``eb`` spanning the plane normal to the unit vector ``u``, with
    ``ea x eb = u``: the frame of a closed form's planar two-link problem."""
    ref = (1.0, 0.0, 0.0) if abs(u[0]) < 0.9 else (0.0, 1.0, 0.0)
    ea = unit(cross(ref, u))
    return ea, cross(u, ea)


def closest_point(axes: Array, points: Array) -> tuple[Array, float]:
    """The point (m) nearest, in least squares, to several lines (unit ``axes`` through
    ``points``), and the largest distance (m) from it to one of them."""
    a = np.zeros((3, 3))
    rhs = np.zeros(3)
    for w, p in zip(axes, points, strict=True):
        proj = np.eye(3) - np.outer(w, w)
        a += proj
        rhs += proj @ p
    x = np.asarray(np.linalg.lstsq(a, rhs, rcond=None)[0], dtype=np.float64)
    miss = max(float(np.linalg.norm((np.eye(3) - np.outer(w, w)) @ (x - p)))
               for w, p in zip(axes, points, strict=True))
    return x, miss


def parallel_deviation(a: V, b: V) -> float:
    """How far two unit vectors are from parallel (or anti-parallel): the sine of their angle."""
    return math.sqrt(max(0.0, 1.0 - dot(a, b) ** 2))


PERPENDICULAR, PARALLEL = "perpendicular", "parallel"
"""How one joint's axis stands to the next's in a closed form's structure."""


def six_axes(axes: Array, points: Array, structure: Sequence[str], tolerance: float,
             error: type[ValueError]) -> tuple[list[V], list[V]]:
    """An arm's zero-configuration joint axes, normalised, and a point on each (m), as
    3-vectors, checked against a closed form's structure.

    Args:
        axes: (6, 3) joint axes at q = 0 (any length).
        points: (6, 3) a point on each axis (m).
        structure: how each joint's axis stands to the next's (5 of :data:`PERPENDICULAR`,
            :data:`PARALLEL`): joint 1 to 2, 2 to 3, ... 5 to 6.
        tolerance: how far from it an axis may be (the sine or cosine of their angle).
        error: the closed form's refusal.

    Raises:
        error: the arm does not have six joints (the message says how many it has), or the
            first condition off by more than ``tolerance`` (``joint 3 parallel to joint 4: off
            by 1.0000``).
    """
    w = [v3(a / np.linalg.norm(a)) for a in np.asarray(axes, float)]
    if len(w) != 6:
        raise error(f"needs 6 revolute joints, has {len(w)}")
    for i, relation in enumerate(structure):
        a, b = w[i], w[i + 1]
        deviation = parallel_deviation(a, b) if relation == PARALLEL else abs(dot(a, b))
        if deviation > tolerance:
            raise error(f"joint {i + 1} {relation} to joint {i + 2}: off by {deviation:.4f}")
    return w, [v3(pt) for pt in np.asarray(points, float)]
