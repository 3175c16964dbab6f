"""Distances and separating axes between the shapes of the compiled broadphase (:mod:`.bounds`):
segments (capsule axes), a cylinder against a box, a point against a solid box. Numba kernels
(:mod:`.jit`); metres.
"""

from __future__ import annotations

import math

from usar_arm.core.spatial import Array
from usar_arm.planning.jit import kernel


@kernel
def _dot(a: Array, b: Array) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@kernel
def segment_distance(p1: Array, d1: Array, p2: Array, d2: Array) -> float:
    """Distance (m) between the segments p1 + s d1 and p2 + t d2, s, t in [0, 1]
    (closest points of two segments, Ericson, Real-Time Collision Detection 5.1.9)."""
    r0, r1, r2 = p1[0] - p2[0], p1[1] - p2[1], p1[2] - p2[2]
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    f = d2[0] * r0 + d2[1] * r1 + d2[2] * r2
    tiny = 1e-300  # only a true zero length is a point: a 1e-9 m segment still counts
    if a <= tiny and e <= tiny:
        return math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    if a <= tiny:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = d1[0] * r0 + d1[1] * r1 + d1[2] * r2
        if e <= tiny:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = _dot(d1, d2)
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > tiny else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    x = r0 + d1[0] * s - d2[0] * t
    y = r1 + d1[1] * s - d2[1] * t
    z = r2 + d1[2] * s - d2[2] * t
    return math.sqrt(x * x + y * y + z * z)


@kernel
def cylinder_box_gap(c: Array, z: Array, r: float, h: float, b_centre: Array,
                      b_axes: Array, b_half: Array, cand: Array) -> float:
    """The largest gap (m) between the projections of the cylinder (centre c, unit axis z,
    radius r, half-length h) and the box (centre, axes as rows (3, 3), half extents) on the
    candidate axes: a lower bound of their distance when positive (they are separated).
    ``cand`` (8, 3) is scratch space for the candidate axes."""
    d0, d1, d2 = c[0] - b_centre[0], c[1] - b_centre[1], c[2] - b_centre[2]
    count = 0
    for i in range(3):
        cand[count] = b_axes[i]
        count += 1
    cand[count] = z
    count += 1
    for i in range(3):
        b = b_axes[i]
        u0 = z[1] * b[2] - z[2] * b[1]
        u1 = z[2] * b[0] - z[0] * b[2]
        u2 = z[0] * b[1] - z[1] * b[0]
        norm = math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
        if norm > 1e-6:
            cand[count, 0], cand[count, 1], cand[count, 2] = u0 / norm, u1 / norm, u2 / norm
            count += 1
    dn = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if dn > 1e-9:
        cand[count, 0], cand[count, 1], cand[count, 2] = d0 / dn, d1 / dn, d2 / dn
        count += 1
    best = -math.inf
    for k in range(count):
        u = cand[k]
        uz = abs(_dot(u, z))
        cyl = uz * h + r * math.sqrt(max(0.0, 1.0 - uz * uz))
        box = (abs(_dot(u, b_axes[0])) * b_half[0] + abs(_dot(u, b_axes[1])) * b_half[1]
               + abs(_dot(u, b_axes[2])) * b_half[2])
        best = max(best, abs(u[0] * d0 + u[1] * d1 + u[2] * d2) - cyl - box)
    return best


@kernel
def point_segment_distance(p: Array, start: Array, d: Array) -> float:
    """Distance (m) from the point ``p`` to the segment start + t d, t in [0, 1]."""
    dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    x, y, z = p[0] - start[0], p[1] - start[1], p[2] - start[2]
    t = 0.0
    if dd > 0.0:
        t = min(max((x * d[0] + y * d[1] + z * d[2]) / dd, 0.0), 1.0)
    x, y, z = x - t * d[0], y - t * d[1], z - t * d[2]
    return math.sqrt(x * x + y * y + z * z)


@kernel
def point_box_distance(x: Array, centre: Array, axes: Array, half: Array) -> float:
    """Distance (m) from the point ``x`` to the solid box (0 inside)."""
    total = 0.0
    for a in range(3):
        u = axes[a]
        t = abs((x[0] - centre[0]) * u[0] + (x[1] - centre[1]) * u[1]
                + (x[2] - centre[2]) * u[2]) - half[a]
        if t > 0.0:
            total += t * t
    return math.sqrt(total)


@kernel
def inner_box_contact(c: Array, z: Array, rho: float, reach: float, b_centre: Array,
                       b_axes: Array, b_half: Array, margin: float, x: Array) -> bool:
    """True when a ball of radius ``rho`` inside the cylinder (its centre on the axis within
    ``reach`` of the centre ``c``) reaches more than ``margin`` into the box: a proof of
    contact. Tries the two ends of that segment and its point nearest the box's centre."""
    t = ((b_centre[0] - c[0]) * z[0] + (b_centre[1] - c[1]) * z[1]
         + (b_centre[2] - c[2]) * z[2])
    t = min(max(t, -reach), reach)
    for offset in (-reach, reach, t):
        for a in range(3):
            x[a] = c[a] + z[a] * offset
        if point_box_distance(x, b_centre, b_axes, b_half) < rho - margin:
            return True
    return False
