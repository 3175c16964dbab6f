"""Balls inside a closed triangle mesh, along its bounding cylinder's axis, for the compiled
verdicts' contact proofs (:mod:`.bounds_scene`). Metres.

python-fcl sees a mesh as its surface. A closed surface (every edge shared by an even number of
triangles) splits space into an inside and an outside; a solid obstacle that holds a point
inside it and a point outside is crossed by the surface, so FCL finds the pair in contact. A ball
inside the mesh that reaches into the obstacle gives the first point, and an obstacle that
reaches out of the mesh's bounding sphere the second. An open mesh gets no balls: its contacts
are FCL's alone.

A candidate centre is inside when rays along three fixed directions cross the surface an odd
number of times each (a ray through an edge could count a crossing twice: three must agree), and
its ball's radius is its exact distance to the nearest triangle (less :data:`SHRINK`).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from usar_arm.core.spatial import Array

STEP = 0.01
"""Spacing (m) of the candidate centres along the axis."""
LEAST = 0.003
"""Smallest radius (m) a ball is kept with."""
SHRINK = 1e-6
"""Taken off each radius (m): the ball stays off the surface by more than rounding."""
PAIRS = 200_000
"""Point-triangle pairs computed at once: a high-poly mesh is taken in blocks of triangles, so
the temporaries stay near 100 MB whatever its size."""
_RAYS = np.array([[0.5773, 0.5774, 0.5774], [-0.2673, 0.5345, 0.8018],
                  [0.8729, -0.2182, 0.4364]])


def closed(faces: np.ndarray[Any, Any]) -> bool:
    """Every edge of ``faces`` (F, 3) is shared by an even number of triangles."""
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if not len(f):
        return False
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts % 2 == 0))


def _blocks(points: Array, triangles: Array) -> list[Array]:
    """``triangles`` in blocks of at most :data:`PAIRS` point-triangle pairs."""
    size = max(1, PAIRS // max(1, len(points)))
    return [triangles[k:k + size] for k in range(0, len(triangles), size)]


def crossings(points: Array, triangles: Array, ray: Array) -> np.ndarray[Any, Any]:
    """Per point (N, 3), how many triangles (T, 3, 3) the ray from it along ``ray`` crosses
    (Moller-Trumbore, both faces)."""
    return np.asarray(sum((_crossings(points, block, ray) for block in
                           _blocks(points, triangles)), np.zeros(len(points), dtype=np.int64)))


def _crossings(points: Array, triangles: Array, ray: Array) -> np.ndarray[Any, Any]:
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2 = b - a, c - a
    p = np.cross(ray, e2)
    det = (e1 * p).sum(axis=1)
    ok = np.abs(det) > 1e-15
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = points[:, None, :] - a[None]
    u = (s * p[None]).sum(axis=2) * inv
    q = np.cross(s, e1[None])
    v = (q * ray).sum(axis=2) * inv
    t = (q * e2[None]).sum(axis=2) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    return np.asarray(hit.sum(axis=1))


def surface_distance(points: Array, triangles: Array) -> Array:
    """Per point (N, 3), its distance (m) to the nearest of ``triangles`` (T, 3, 3): the
    closest point on each triangle by its Voronoi regions (vertex, edge, face)."""
    return np.asarray(np.min([_distance(points, block) for block in _blocks(points, triangles)],
                             axis=0))


def _distance(points: Array, triangles: Array) -> Array:
    a, b, c = (triangles[None, :, k] for k in range(3))
    p = points[:, None, :]
    ab, ac, ap = b - a, c - a, p - a

    def dot(x: Array, y: Array) -> Array:
        return np.asarray((x * y).sum(axis=2))

    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp, cp = p - b, p - c
    d3, d4, d5, d6 = dot(ab, bp), dot(ac, bp), dot(ab, cp), dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v_in, w_in = vb / denom, vc / denom
        t_ab = np.clip(d1 / (d1 - d3), 0, 1)
        t_ac = np.clip(d2 / (d2 - d6), 0, 1)
        t_bc = np.clip((d4 - d3) / ((d4 - d3) + (d5 - d6)), 0, 1)
    closest = a + ab * v_in[..., None] + ac * w_in[..., None]  # inside the face
    regions = [  # (where, closest point), the later ones taking precedence (Ericson's order)
        ((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), b + (c - b) * t_bc[..., None]),
        ((vb <= 0) & (d2 >= 0) & (d6 <= 0), a + ac * t_ac[..., None]),
        ((d6 >= 0) & (d5 <= d6), np.broadcast_to(c, closest.shape)),
        ((vc <= 0) & (d1 >= 0) & (d3 <= 0), a + ab * t_ab[..., None]),
        ((d3 >= 0) & (d4 <= d3), np.broadcast_to(b, closest.shape)),
        ((d1 <= 0) & (d2 <= 0), np.broadcast_to(a, closest.shape)),
    ]
    for where, point in regions:
        closest = np.where(where[..., None], point, closest)
    closest = np.where(np.isfinite(closest), closest, a)  # (degenerate triangles: a vertex)
    return np.asarray(np.sqrt(((p - closest) ** 2).sum(axis=2)).min(axis=1))


def axis_balls(vertices: Array, faces: np.ndarray[Any, Any], half: float) -> Array:
    """(K, 4) centres and radii of balls inside the closed mesh ``vertices``, ``faces``, their
    centres on the z axis within ``half`` (m) of the origin every :data:`STEP`; (0, 4) for an
    open mesh."""
    if not closed(faces):
        return np.zeros((0, 4))
    triangles = np.asarray(vertices, dtype=float)[np.asarray(faces, dtype=np.int64)]
    n = max(1, int(np.floor(2 * half / STEP)))
    z = np.linspace(-half, half, n + 1)
    centres = np.column_stack([np.zeros_like(z), np.zeros_like(z), z])
    inside = np.ones(len(z), dtype=bool)
    for ray in _RAYS / np.linalg.norm(_RAYS, axis=1, keepdims=True):
        inside &= crossings(centres, triangles, ray) % 2 == 1
    radius = surface_distance(centres, triangles) - SHRINK
    keep = inside & (radius >= LEAST)
    return np.column_stack([centres[keep], radius[keep]])


@functools.lru_cache(maxsize=64)
def _cached(vertices: bytes, faces: bytes, frame: bytes, half: float) -> Array:
    v = np.frombuffer(vertices).reshape(-1, 3)
    t = np.frombuffer(frame).reshape(4, 4)
    balls = axis_balls(v @ t[:3, :3].T + t[:3, 3],
                       np.frombuffer(faces, dtype=np.int64).reshape(-1, 3), half)
    balls.setflags(write=False)
    return balls


def axis_balls_in(vertices: Array, faces: np.ndarray[Any, Any], frame: Array | None,
                  half: float) -> Array:
    """:func:`axis_balls` of a mesh whose pose in its cylinder's frame is ``frame`` (4x4;
    None: the same frame), computed once per mesh, frame and half-length in a process."""
    t = np.eye(4) if frame is None else np.asarray(frame, float)
    return _cached(np.ascontiguousarray(vertices, dtype=float).tobytes(),
                   np.ascontiguousarray(faces, dtype=np.int64).tobytes(),
                   np.ascontiguousarray(t).tobytes(), float(half))
