"""Balls that cover a triangle mesh's surface, in two levels, for the compiled verdicts
(:mod:`.bounds_balls`): where a mesh's one bounding cylinder is too loose to clear a pair, its
balls often are not.

python-fcl sees a mesh as its surface: a mesh is in contact with another body when one of its
triangles touches it. Every triangle lies in the ball around its three vertices (a triangle is
their convex hull), so balls that hold every triangle's vertices hold the surface, and a
pair whose balls are all apart is apart for python-fcl too. Triangles are first split until no
edge is longer than half a leaf cell (large flat faces would otherwise give large balls); a
leaf ball holds the triangles whose centroids share a cell of :data:`LEAF` m, a group ball its
leaves in a cell of :data:`GROUP` m, so that a test can skip a whole group at once. Metres.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning.element_fit import GROW

LEAF = 0.02
"""Edge of the cells whose triangles share a leaf ball (m): leaves of about 1.5 cm radius."""
GROUP = 0.08
"""Edge of the cells whose leaves share a group ball (m)."""
Indices = np.ndarray[Any, np.dtype[np.int64]]


@dataclass(frozen=True)
class BallCover:
    """Two levels of balls around a surface, in the frame of its vertices.

    Attributes:
        groups: (G, 6) per group: centre (3), radius, its first leaf and one past its last.
        leaves: (M, 4) centre (3) and radius of each leaf, the leaves of one group together.
    """

    groups: Array
    leaves: Array


def split_triangles(triangles: Array, longest: float) -> Array:
    """``triangles`` (T, 3, 3) split at the midpoint of their longest edge until no edge is
    longer than ``longest`` (m); the pieces cover the same surface."""
    done = []
    todo = np.asarray(triangles, dtype=float).reshape(-1, 3, 3)
    while len(todo):
        edges = np.linalg.norm(todo[:, [1, 2, 0]] - todo, axis=2)  # 01, 12, 20
        long = edges.max(axis=1) > longest
        done.append(todo[~long])
        todo = todo[long]
        k = edges[long].argmax(axis=1)
        rows = np.arange(len(todo))
        a, b, c = todo[rows, k], todo[rows, (k + 1) % 3], todo[rows, (k + 2) % 3]
        mid = (a + b) / 2
        todo = np.concatenate([np.stack([a, mid, c], axis=1), np.stack([mid, b, c], axis=1)])
    return np.concatenate(done) if done else np.zeros((0, 3, 3))


def _balls(points: list[Array]) -> Array:
    """(len(points), 4): per point set, the centre of its bounding box and the radius that
    holds every point."""
    out = np.empty((len(points), 4))
    for n, p in enumerate(points):
        centre = (p.min(axis=0) + p.max(axis=0)) / 2
        out[n, :3] = centre
        out[n, 3] = float(np.sqrt(((p - centre) ** 2).sum(axis=1)).max()) + GROW
    return out


def _cells(points: Array, size: float) -> Indices:
    """Per point (N, 3), the index of its cell of edge ``size`` among the occupied cells."""
    _, index = np.unique(np.floor(points / size).astype(np.int64), axis=0, return_inverse=True)
    return np.asarray(index, dtype=np.int64).reshape(-1)


def cover(vertices: Array, faces: np.ndarray[Any, Any], leaf: float = LEAF,
          group: float = GROUP) -> BallCover:
    """The :class:`BallCover` of the surface of ``vertices`` (V, 3) and ``faces`` (F, 3)."""
    tris = split_triangles(np.asarray(vertices, float)[np.asarray(faces, np.int64)], leaf / 2)
    if not len(tris):
        raise ValueError("a mesh without triangles has no surface to cover")
    cell = _cells(tris.mean(axis=1), leaf)
    order = np.argsort(cell, kind="stable")
    starts = np.searchsorted(cell[order], np.arange(1, cell.max() + 1))
    leaves = _balls([t.reshape(-1, 3) for t in np.split(tris[order], starts)])
    owner = _cells(leaves[:, :3], group)
    order = np.argsort(owner, kind="stable")
    leaves, owner = leaves[order], owner[order]
    bounds = np.searchsorted(owner, np.arange(owner.max() + 2))
    groups = np.empty((len(bounds) - 1, 6))
    for g in range(len(groups)):
        members = leaves[bounds[g]:bounds[g + 1]]
        centre = (members[:, :3].min(axis=0) + members[:, :3].max(axis=0)) / 2
        reach = np.sqrt(((members[:, :3] - centre) ** 2).sum(axis=1)) + members[:, 3]
        groups[g, :3], groups[g, 3] = centre, float(reach.max()) + GROW
        groups[g, 4], groups[g, 5] = bounds[g], bounds[g + 1]
    return BallCover(groups, leaves)


@functools.lru_cache(maxsize=64)
def _cached(vertices: bytes, faces: bytes, frame: bytes) -> BallCover:
    v = np.frombuffer(vertices).reshape(-1, 3)
    t = np.frombuffer(frame).reshape(4, 4)
    return cover(v @ t[:3, :3].T + t[:3, 3], np.frombuffer(faces, dtype=np.int64).reshape(-1, 3))


def cover_in(vertices: Array, faces: np.ndarray[Any, Any], frame: Array | None) -> BallCover:
    """:func:`cover` of a mesh whose pose in the wanted frame is ``frame`` (4x4; None: the
    same frame), computed once per mesh and frame in a process."""
    t = np.eye(4) if frame is None else np.asarray(frame, float)
    return _cached(np.ascontiguousarray(vertices, dtype=float).tobytes(),
                   np.ascontiguousarray(faces, dtype=np.int64).tobytes(),
                   np.ascontiguousarray(t).tobytes())
