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
    return _segments_apart(p1[0] - p2[0], p1[1] - p2[1], p1[2] - p2[2], d1[0], d1[1], d1[2],
                           d2[0], d2[1], d2[2])


@kernel
def rows_distance(seg: Array, row: int, i: int, j: int) -> float:
    """:func:`segment_distance` between the segments of bodies ``i`` and ``j`` in ``seg``
    (R, L, 3): starts in row ``row``, directions in row ``row + 1``. Read by index, so that a
    kernel's inner loop makes no array views (each costs a reference count)."""
    return _segments_apart(seg[row, i, 0] - seg[row, j, 0], seg[row, i, 1] - seg[row, j, 1],
                           seg[row, i, 2] - seg[row, j, 2], seg[row + 1, i, 0],
                           seg[row + 1, i, 1], seg[row + 1, i, 2], seg[row + 1, j, 0],
                           seg[row + 1, j, 1], seg[row + 1, j, 2])


@kernel
def _segments_apart(r0: float, r1: float, r2: float, u0: float, u1: float, u2: float,
                    v0: float, v1: float, v2: float) -> float:
    """:func:`segment_distance` from p1 - p2 = (r0, r1, r2), d1 = u and d2 = v."""
    a = u0 * u0 + u1 * u1 + u2 * u2
    e = v0 * v0 + v1 * v1 + v2 * v2
    f = v0 * r0 + v1 * r1 + v2 * r2
    tiny = 1e-300  # only a true zero length is a point: a 1e-9 m segment still counts
    if a <= tiny and e <= tiny:
        return math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    if a <= tiny:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = u0 * r0 + u1 * r1 + u2 * r2
        if e <= tiny:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = u0 * v0 + u1 * v1 + u2 * v2
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > tiny else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    x = r0 + u0 * s - v0 * t
    y = r1 + u1 * s - v1 * t
    z = r2 + u2 * s - v2 * t
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
    return xyz_segment_distance(p[0], p[1], p[2], start[0], start[1], start[2], d[0], d[1], d[2])


@kernel
def xyz_segment_distance(p0: float, p1: float, p2: float, s0: float, s1: float, s2: float,
                         d0: float, d1: float, d2: float) -> float:
    """:func:`point_segment_distance` from coordinates: kernels call it in their inner loops
    with values read by index, making no array views (each costs a reference count)."""
    dd = d0 * d0 + d1 * d1 + d2 * d2
    x, y, z = p0 - s0, p1 - s1, p2 - s2
    t = 0.0
    if dd > 0.0:
        t = min(max((x * d0 + y * d1 + z * d2) / dd, 0.0), 1.0)
    x, y, z = x - t * d0, y - t * d1, z - t * d2
    return math.sqrt(x * x + y * y + z * z)


@kernel
def point_box_distance(x: Array, centre: Array, axes: Array, half: Array) -> float:
    """Distance (m) from the point ``x`` to the solid box (0 inside)."""
    return xyz_box_distance(x[0], x[1], x[2], centre[0], centre[1], centre[2], axes, half[0],
                            half[1], half[2])


@kernel
def xyz_box_distance(x0: float, x1: float, x2: float, c0: float, c1: float, c2: float,
                     axes: Array, h0: float, h1: float, h2: float) -> float:
    """:func:`point_box_distance` from coordinates (as :func:`xyz_segment_distance`): the
    point, the box's centre, its axes as rows (3, 3) and its half extents."""
    total = 0.0
    for a in range(3):
        t = abs((x0 - c0) * axes[a, 0] + (x1 - c1) * axes[a, 1] + (x2 - c2) * axes[a, 2])
        t -= h0 if a == 0 else (h1 if a == 1 else h2)
        if t > 0.0:
            total += t * t
    return math.sqrt(total)


GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
"""The golden section's ratio (:func:`inner_box_contact`'s search along the axis)."""
SEARCH = 48
"""Golden-section steps of :func:`inner_box_contact` (the interval shrinks by 0.618 a step:
a 1 m segment to 1e-10 m)."""


@kernel
def _axis_box_distance(c: Array, z: Array, offset: float, b_centre: Array, b_axes: Array,
                       b_half: Array, x: Array) -> float:
    """Distance (m) from the axis point ``c + offset z`` (into scratch ``x``) to the solid box."""
    for a in range(3):
        x[a] = c[a] + z[a] * offset
    return point_box_distance(x, b_centre, b_axes, b_half)


@kernel
def inner_box_contact(c: Array, z: Array, rho: float, reach: float, b_centre: Array,
                       b_axes: Array, b_half: Array, margin: float, x: Array) -> bool:
    """True when a ball of radius ``rho`` inside the cylinder (its centre on the axis within
    ``reach`` of the centre ``c``) reaches more than ``margin`` into the box: a proof of
    contact (every point tried is a real centre, so the answer is sound however the point was
    found).

    The centre is the segment's point nearest the box: where the segment crosses the box
    (clipped against the box's three slabs), the middle of the part inside; else the minimum
    of the distance along the segment, a convex function, by golden section. A link that goes
    through a thin, wide slab (a floor) far from the slab's centre is proven this way."""
    limit = rho - margin
    if limit <= 0.0:
        return False
    lo, hi = -reach, reach
    for a in range(3):
        u = b_axes[a]
        p = ((c[0] - b_centre[0]) * u[0] + (c[1] - b_centre[1]) * u[1]
             + (c[2] - b_centre[2]) * u[2])
        d = z[0] * u[0] + z[1] * u[1] + z[2] * u[2]
        if abs(d) <= 1e-300:
            if abs(p) > b_half[a]:
                hi = lo - 1.0  # parallel to this slab and outside it
        else:
            t1, t2 = (-b_half[a] - p) / d, (b_half[a] - p) / d
            lo, hi = max(lo, min(t1, t2)), min(hi, max(t1, t2))
    if lo <= hi:
        return _axis_box_distance(c, z, 0.5 * (lo + hi), b_centre, b_axes, b_half, x) < limit
    lo, hi = -reach, reach
    if (_axis_box_distance(c, z, lo, b_centre, b_axes, b_half, x) < limit
            or _axis_box_distance(c, z, hi, b_centre, b_axes, b_half, x) < limit):
        return True
    m1, m2 = hi - GOLDEN * (hi - lo), lo + GOLDEN * (hi - lo)
    f1 = _axis_box_distance(c, z, m1, b_centre, b_axes, b_half, x)
    f2 = _axis_box_distance(c, z, m2, b_centre, b_axes, b_half, x)
    for _ in range(SEARCH):
        if f1 < limit or f2 < limit:
            return True
        if f1 <= f2:  # the minimum is in [lo, m2]
            hi, m2, f2 = m2, m1, f1
            m1 = hi - GOLDEN * (hi - lo)
            f1 = _axis_box_distance(c, z, m1, b_centre, b_axes, b_half, x)
        else:  # in [m1, hi]
            lo, m1, f1 = m1, m2, f2
            m2 = lo + GOLDEN * (hi - lo)
            f2 = _axis_box_distance(c, z, m2, b_centre, b_axes, b_half, x)
    return f1 < limit or f2 < limit


RIM = 2.0
"""The balls of the rim proofs (:func:`rim_box_contact`, :func:`rim_cylinders_contact`) have
this many proof margins as radius: a rim that reaches about 1.8 margins into the other shape
is proven (a smaller ball proves shallower contacts; it must exceed one margin)."""


@kernel
def point_cylinder_distance(x: Array, c: Array, z: Array, r: float, h: float) -> float:
    """Distance (m) from the point ``x`` to the solid cylinder (centre ``c``, unit axis ``z``,
    radius ``r``, half-length ``h``; 0 inside)."""
    v0, v1, v2 = x[0] - c[0], x[1] - c[1], x[2] - c[2]
    t = v0 * z[0] + v1 * z[1] + v2 * z[2]
    w0, w1, w2 = v0 - t * z[0], v1 - t * z[1], v2 - t * z[2]
    radial = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2) - r
    axial = abs(t) - h
    return math.sqrt(max(radial, 0.0) ** 2 + max(axial, 0.0) ** 2)


@kernel
def cylinder_support(c: Array, z: Array, r: float, h: float, d0: float, d1: float, d2: float,
                     x: Array) -> None:
    """The point of the solid cylinder (as :func:`point_cylinder_distance`) farthest along
    the direction (d0, d1, d2), into ``x`` (the end disc's centre when the direction is the
    axis; the middle of the axis when it is square to it)."""
    t = d0 * z[0] + d1 * z[1] + d2 * z[2]
    w0, w1, w2 = d0 - t * z[0], d1 - t * z[1], d2 - t * z[2]
    nw = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    s = h if t > 0.0 else (-h if t < 0.0 else 0.0)
    k = r / nw if nw > 1e-12 else 0.0
    for a in range(3):
        x[a] = c[a] + s * z[a]
    x[0] += k * w0
    x[1] += k * w1
    x[2] += k * w2


@kernel
def rim_box_contact(c: Array, z: Array, r: float, h: float, b_centre: Array, b_axes: Array,
                    b_half: Array, margin: float, x: Array) -> bool:
    """True when a small ball inside the cylinder (radius :data:`RIM` margins, centred in the
    cylinder shrunk by that radius) reaches more than ``margin`` into the box: the proof for
    a rim or an edge that dips into a box, which the balls on the axis do not reach. The
    centres tried are the shrunk cylinder's points deepest along each of the box's six face
    normals and towards the box's centre (any centre in the shrunk cylinder is sound)."""
    ball = RIM * margin
    if r <= ball or h <= ball:
        return False
    limit = ball - margin
    rs, hs = r - ball, h - ball
    for a in range(3):
        u = b_axes[a]
        for sign in (-1.0, 1.0):
            cylinder_support(c, z, rs, hs, sign * u[0], sign * u[1], sign * u[2], x)
            if point_box_distance(x, b_centre, b_axes, b_half) < limit:
                return True
    cylinder_support(c, z, rs, hs, b_centre[0] - c[0], b_centre[1] - c[1], b_centre[2] - c[2],
                     x)
    return point_box_distance(x, b_centre, b_axes, b_half) < limit


@kernel
def _rim_into(c1: Array, z1: Array, r1: float, h1: float, c2: Array, z2: Array, r2: float,
              h2: float, ball: float, limit: float, x: Array) -> bool:
    """:func:`rim_cylinders_contact` one way: the shrunk first cylinder's points deepest
    along the second's axis (both ways), towards its axis and towards its centre."""
    rs, hs = r1 - ball, h1 - ball
    for sign in (-1.0, 1.0):
        cylinder_support(c1, z1, rs, hs, sign * z2[0], sign * z2[1], sign * z2[2], x)
        if point_cylinder_distance(x, c2, z2, r2, h2) < limit:
            return True
    v0, v1, v2 = c2[0] - c1[0], c2[1] - c1[1], c2[2] - c1[2]
    cylinder_support(c1, z1, rs, hs, v0, v1, v2, x)
    if point_cylinder_distance(x, c2, z2, r2, h2) < limit:
        return True
    t = v0 * z2[0] + v1 * z2[1] + v2 * z2[2]
    cylinder_support(c1, z1, rs, hs, v0 - t * z2[0], v1 - t * z2[1], v2 - t * z2[2], x)
    return point_cylinder_distance(x, c2, z2, r2, h2) < limit


@kernel
def rim_cylinders_contact(c1: Array, z1: Array, r1: float, h1: float, c2: Array, z2: Array,
                          r2: float, h2: float, margin: float, x: Array) -> bool:
    """True when a small ball inside one solid cylinder (as :func:`rim_box_contact`) reaches
    more than ``margin`` into the other (centre, unit axis, radius, half-length each): the
    rim proof between two cylinders, tried both ways."""
    ball = RIM * margin
    limit = ball - margin
    return ((min(r1, h1) > ball and _rim_into(c1, z1, r1, h1, c2, z2, r2, h2, ball, limit, x))
            or (min(r2, h2) > ball
                and _rim_into(c2, z2, r2, h2, c1, z1, r1, h1, ball, limit, x)))
