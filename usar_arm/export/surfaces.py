"""Surfaces for the pictures: scene shapes and link cylinders as short polygons (m).

Matplotlib sorts 3D polygons by their centroid depth (painter's algorithm), so long faces are
cut into pieces no longer than :data:`PIECE`; :class:`Faces` gathers polygons with their colours
into one lit, depth-sorted collection and clips oversized ones (a floor) to the view.
"""

from __future__ import annotations

import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from usar_arm.core.spatial import Array
from usar_arm.planning.scene import Box, CylinderShape, Shape, Sphere

PIECE = 0.2
"""Longest edge (m) of a face piece: short pieces keep the painter's algorithm honest."""


def _grid(origin: Array, u: Array, v: Array, piece: float) -> list[Array]:
    """The parallelogram origin + [0, 1] u + [0, 1] v cut into pieces no longer than ``piece``."""
    nu = max(1, int(np.ceil(np.linalg.norm(u) / piece)))
    nv = max(1, int(np.ceil(np.linalg.norm(v) / piece)))
    a, b = np.arange(nu)[:, None, None], np.arange(nv)[None, :, None]
    corners = [origin + (a + i) / nu * u + (b + j) / nv * v
               for i, j in ((0, 0), (1, 0), (1, 1), (0, 1))]
    return list(np.stack(corners, axis=2).reshape(-1, 4, 3))


def _place(polys: list[Array], pose: Array) -> list[Array]:
    return [p @ pose[:3, :3].T + pose[:3, 3] for p in polys]


def _circle(radius: float, z: float, n: int = 24) -> Array:
    a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.full(n, z)])


def cylinder(radius: float, length: float, pose: Array, piece: float = PIECE) -> list[Array]:
    """Faces of a cylinder along its pose's z axis, centred there (m)."""
    top, bottom = _circle(radius, length / 2), _circle(radius, -length / 2)
    polys = [top, bottom[::-1]]
    for i in range(len(top)):
        j = (i + 1) % len(top)
        polys += _grid(bottom[i], bottom[j] - bottom[i], top[i] - bottom[i], piece)
    return _place(polys, pose)


def shape_faces(shape: Shape, pose: Array, piece: float = PIECE) -> list[Array]:
    """Faces (polygons, m, base_link) of an obstacle."""
    if isinstance(shape, CylinderShape):
        return cylinder(shape.radius, shape.length, pose, piece)
    if isinstance(shape, Box):
        h = np.asarray(shape.size, dtype=float) / 2
        polys = []
        for k in range(3):
            u, v = np.zeros(3), np.zeros(3)
            u[(k + 1) % 3], v[(k + 2) % 3] = 2 * h[(k + 1) % 3], 2 * h[(k + 2) % 3]
            for sign in (-1.0, 1.0):
                origin = -h.copy()
                origin[k] = sign * h[k]
                polys += _grid(origin, u, v, piece)
        return _place(polys, pose)
    if isinstance(shape, Sphere):
        th, ph = np.linspace(0, 2 * np.pi, 21), np.linspace(-np.pi / 2, np.pi / 2, 12)
        pts = shape.radius * np.stack([np.cos(ph)[:, None] * np.cos(th), np.cos(ph)[:, None]
                                       * np.sin(th), np.sin(ph)[:, None] * np.ones_like(th)], -1)
        polys = [np.array([pts[i, j], pts[i, j + 1], pts[i + 1, j + 1], pts[i + 1, j]])
                 for i in range(len(ph) - 1) for j in range(len(th) - 1)]
        return _place(polys, pose)
    vertices = np.asarray(shape.vertices, dtype=float)
    return _place(list(vertices[np.asarray(shape.faces, dtype=int)]), pose)


def outline(shape: Shape, pose: Array) -> list[Array]:
    """Polylines (m) that show an obstacle's form: box edges, cylinder rims, sphere equator,
    mesh edges where the surface folds by more than 30 deg."""
    if isinstance(shape, Box):
        c = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
        c *= np.asarray(shape.size) / 2
        lines = [c[[i, j]] for i in range(8) for j in range(i + 1, 8)
                 if np.count_nonzero(c[i] != c[j]) == 1]
    elif isinstance(shape, CylinderShape):
        lines = [np.vstack([r, r[:1]]) for r in (_circle(shape.radius, shape.length / 2, 48),
                                                  _circle(shape.radius, -shape.length / 2, 48))]
    elif isinstance(shape, Sphere):
        r = _circle(shape.radius, 0.0, 48)
        lines = [np.vstack([r, r[:1]])]
    else:
        v, f = np.asarray(shape.vertices, float), np.asarray(shape.faces, int)
        n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        owners: dict[tuple[int, int], list[int]] = {}
        for i, tri in enumerate(f):
            for a, b in ((0, 1), (1, 2), (2, 0)):
                owners.setdefault((min(tri[a], tri[b]), max(tri[a], tri[b])), []).append(i)
        lines = [v[list(e)] for e, fs in owners.items()
                 if len(fs) != 2 or abs(float(n[fs[0]] @ n[fs[1]])) < np.cos(np.radians(30))]
    return _place(lines, pose)


def _clip(poly: Array, lo: Array, hi: Array) -> Array:
    """Sutherland-Hodgman: the part of a convex-or-not polygon inside the box [lo, hi]."""
    for k in range(3):
        for sign, bound in ((1.0, lo[k]), (-1.0, hi[k])):
            if len(poly) == 0:
                return poly
            d = sign * (poly[:, k] - bound)
            inside = d >= -1e-9
            out = []
            for i in range(len(poly)):
                j = (i + 1) % len(poly)
                if inside[i]:
                    out.append(poly[i])
                if inside[i] != inside[j]:
                    out.append(poly[i] + d[i] / (d[i] - d[j]) * (poly[j] - poly[i]))
            poly = np.array(out).reshape(-1, 3)
    return poly


class Faces:
    """Polygons (m) with an RGBA colour each, drawn as one depth-sorted collection."""

    def __init__(self, polys: list[Array] | None = None, rgba: tuple[float, ...] = ()) -> None:
        self.polys: list[Array] = []
        self.colors: list[tuple[float, ...]] = []
        if polys:
            self.add(polys, rgba)

    def __len__(self) -> int:
        return len(self.polys)

    def add(self, polys: list[Array], rgba: tuple[float, ...]) -> None:
        self.polys += polys
        self.colors += [tuple(rgba)] * len(polys)

    def points(self) -> Array:
        return np.vstack(self.polys) if self.polys else np.zeros((0, 3))

    def __add__(self, other: Faces) -> Faces:
        out = Faces()
        out.polys, out.colors = self.polys + other.polys, self.colors + other.colors
        return out

    def clipped(self, lo: Array, hi: Array) -> Faces:
        """The parts inside the box [lo, hi] (m); slivers are dropped."""
        out = Faces()
        for poly, rgba in zip(self.polys, self.colors, strict=True):
            p = _clip(poly, lo, hi)
            if len(p) >= 3 and np.linalg.norm(np.cross(p[1] - p[0], p[-1] - p[0])) > 1e-9:
                out.add([p], rgba)
        return out

    def collection(self, light: Array, zorder: float) -> Poly3DCollection:
        """A Poly3DCollection, each face lit by ``light`` (two-sided Lambert + ambient);
        opaque faces get an edge of their own colour so the pieces show no seams."""
        rgba = np.array(self.colors, dtype=float)
        normals = np.array([np.cross(p[1] - p[0], p[-1] - p[0]) for p in self.polys])
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
        shade = 0.55 + 0.45 * np.abs(normals @ light)
        rgba[:, :3] *= shade[:, None]
        opaque = rgba[:, 3] >= 0.999
        return Poly3DCollection(self.polys, facecolors=rgba, edgecolors=rgba,
                                linewidths=np.where(opaque, 0.5, 0.0),
                                zorder=zorder)
