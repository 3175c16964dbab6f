"""Bounding cylinders of collision elements, for the compiled verdicts (:mod:`.bounds`), which
see every robot body as a cylinder.

A cylinder element is its own bound (exact). A sphere is the cylinder of its radius and
half-length (its one inner ball is the sphere itself), a capsule the cylinder around it (its
inner balls are the capsule's own): both exact for contact proofs too. A box gets the cylinder
along its longest edge through its corners; a mesh the cylinder along its vertices' principal
axis that holds every vertex (so their convex hull, so the mesh): these only ever clear pairs,
python-fcl decides the rest with the real shape. Metres."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from usar_arm.core.shapes import Box, Capsule, CylinderShape, Mesh, Shape, Sphere
from usar_arm.core.spatial import Array

GROW = 1e-9
"""Absolute growth (m) of a fitted radius and half-length against rounding."""


@dataclass(frozen=True)
class BoundingCylinder:
    """A cylinder around a shape.

    Attributes:
        frame: 4x4 pose of the cylinder (its axis along z, centred) in the shape's frame.
        radius, half: m. exact: True when it is the shape itself, or its inner balls lie
            inside the shape (a proven overlap of those balls is a contact of the shape).
    """

    frame: Array
    radius: float
    half: float
    exact: bool


def _along(axis: int) -> Array:
    """A rotation taking z onto coordinate axis ``axis`` (0, 1, 2)."""
    if axis == 2:
        return np.eye(3)
    if axis == 0:
        return np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    return np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def fit_points(points: Array) -> tuple[Array, float, float]:
    """The cylinder along ``points``' principal axis holding every point: (frame 4x4, radius,
    half-length), m."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    centred = p - p.mean(axis=0)
    rot = np.linalg.svd(centred, full_matrices=True)[2].T if len(p) > 1 else np.eye(3)
    if np.linalg.det(rot) < 0:
        rot[:, 2] = -rot[:, 2]
    rot = rot[:, [1, 2, 0]]  # the principal axis as the cylinder's z
    local = p @ rot
    lo, hi = local.min(axis=0), local.max(axis=0)
    centre = (lo + hi) / 2
    radius = float(np.sqrt(((local[:, :2] - centre[:2]) ** 2).sum(axis=1)).max())
    frame = np.eye(4)
    frame[:3, :3], frame[:3, 3] = rot, rot @ centre
    return frame, radius + GROW, float((hi[2] - lo[2]) / 2) + GROW


def bounding_cylinder(shape: Shape) -> BoundingCylinder:
    """The cylinder the compiled verdicts use for ``shape``."""
    eye = np.eye(4)
    if isinstance(shape, CylinderShape):
        return BoundingCylinder(eye, shape.radius, shape.length / 2, True)
    if isinstance(shape, Sphere):
        return BoundingCylinder(eye, shape.radius, shape.radius, True)
    if isinstance(shape, Capsule):
        return BoundingCylinder(eye, shape.radius, shape.length / 2 + shape.radius, True)
    if isinstance(shape, Box):
        extents = np.asarray(shape.size, float) / 2
        axis = int(np.argmax(extents))
        a, b = (float(extents[k]) for k in range(3) if k != axis)
        frame = np.eye(4)
        frame[:3, :3] = _along(axis)
        return BoundingCylinder(frame, float(np.hypot(a, b)) + GROW,
                                float(extents[axis]) + GROW, False)
    if isinstance(shape, Mesh):
        frame, radius, length = fit_points(shape.vertices)
        return BoundingCylinder(frame, radius, length, False)
    raise TypeError(f"unsupported shape {shape!r}")


def padded(shape: Shape, padding: float) -> Shape:
    """``shape`` grown by ``padding`` m in every direction (a box by 2 padding per edge).

    Raises:
        ValueError: a mesh (it cannot be grown exactly) with a positive padding.
    """
    if padding == 0.0:
        return shape
    if isinstance(shape, CylinderShape):
        return CylinderShape(shape.radius + padding, shape.length + 2 * padding)
    if isinstance(shape, Sphere):
        return Sphere(shape.radius + padding)
    if isinstance(shape, Capsule):
        return Capsule(shape.radius + padding, shape.length)
    if isinstance(shape, Box):
        return Box(tuple(s + 2 * padding for s in shape.size))  # type: ignore[arg-type]
    raise ValueError(f"a padding of {padding} m cannot grow a mesh collision element "
                     f"({shape.source}); use padding 0 with mesh robots")
