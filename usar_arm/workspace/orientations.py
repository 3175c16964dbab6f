"""Deterministic, near-uniform sets of tool orientations.

The full set is a Super-Fibonacci spiral on the unit quaternions (Alexa, "Super-Fibonacci
Spirals: Fast, Low-Discrepancy Sampling of SO(3)", CVPR 2022): n rotations with no seed, no
randomness and no clustering, so a reachability map is the same wherever and whenever it is
computed. A restricted set (the tool's z axis within a cone about a direction, e.g. pointing
down +/- 30 deg) is picked from a denser spiral by farthest-point selection inside the cone,
starting from the rotation that best aligns the tool with the cone's axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usar_arm.core.spatial import Array

PHI = math.sqrt(2.0)
PSI = 1.533751168755204288118041
"""The two irrational steps of the Super-Fibonacci spiral (sqrt 2 and the root of
psi^4 = psi + 4)."""


@dataclass(frozen=True)
class OrientationSet:
    """Tool orientations in base_link.

    Attributes:
        quaternions: (n, 4) unit quaternions (w, x, y, z), one per orientation, w >= 0.
        cone_deg: half-angle (deg) of the cone the tool z axis was restricted to, or None.
        axis: the cone's axis (unit 3-vector in base_link), or None.
    """

    quaternions: Array
    cone_deg: float | None = None
    axis: tuple[float, float, float] | None = None

    def __len__(self) -> int:
        return int(self.quaternions.shape[0])

    def matrices(self) -> Array:
        """(n, 3, 3) rotation matrices."""
        return quaternions_to_matrices(self.quaternions)


def super_fibonacci(n: int) -> Array:
    """(n, 4) unit quaternions (w, x, y, z) spread near-uniformly over SO(3), w >= 0."""
    if n < 1:
        raise ValueError(f"an orientation set needs at least 1 orientation, got {n}")
    s = np.arange(n, dtype=float) + 0.5
    r = np.sqrt(s / n)
    big_r = np.sqrt(1.0 - s / n)
    alpha = 2.0 * math.pi * s / PHI
    beta = 2.0 * math.pi * s / PSI
    q = np.stack([r * np.sin(alpha), r * np.cos(alpha), big_r * np.sin(beta),
                  big_r * np.cos(beta)], axis=1)
    q[q[:, 0] < 0] *= -1.0  # q and -q are the same rotation: keep the w >= 0 half
    return q


def quaternions_to_matrices(q: Array) -> Array:
    """(n, 3, 3) rotation matrices of (n, 4) unit quaternions (w, x, y, z)."""
    w, x, y, z = (q[:, i] for i in range(4))
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1),
    ], axis=1)


def geodesic(a: Array, b: Array) -> Array:
    """Rotation angles (rad) between quaternions ``a`` (n, 4) and ``b`` (4,) or (n, 4)."""
    dot = np.abs(np.sum(a * b, axis=-1))
    return 2.0 * np.arccos(np.clip(dot, -1.0, 1.0))


def orientation_set(count: int, cone_deg: float | None = None,
                    axis: tuple[float, float, float] = (0.0, 0.0, -1.0)) -> OrientationSet:
    """``count`` tool orientations: all of SO(3), or those whose tool z axis lies within
    ``cone_deg`` degrees of ``axis`` (base_link; the default points straight down).

    Raises:
        ValueError: count < 1, a cone outside (0, 180] deg, or a zero axis.
    """
    if count < 1:
        raise ValueError(f"--orientations must be at least 1, got {count}")
    if cone_deg is None:
        return OrientationSet(super_fibonacci(count))
    if not 0.0 < cone_deg <= 180.0:
        raise ValueError(f"a cone half-angle is in (0, 180] degrees, got {cone_deg}")
    a = np.asarray(axis, float)
    norm = float(np.linalg.norm(a))
    if norm < 1e-9:
        raise ValueError("the cone's axis is a zero vector")
    a = a / norm
    fraction = (1.0 - math.cos(math.radians(cone_deg))) / 2.0  # of the sphere of directions
    pool_size = max(8 * count, math.ceil(16 * count / fraction))
    pool = super_fibonacci(pool_size)
    tool_z = quaternions_to_matrices(pool)[:, :, 2]
    inside = pool[tool_z @ a >= math.cos(math.radians(cone_deg)) - 1e-12]
    if len(inside) < count:
        raise ValueError(f"cannot pick {count} orientations within {cone_deg} deg "
                         f"(only {len(inside)} candidates)")
    chosen = _farthest_points(inside, quaternions_to_matrices(inside)[:, :, 2] @ a, count)
    return OrientationSet(chosen, float(cone_deg), (float(a[0]), float(a[1]), float(a[2])))


def _farthest_points(pool: Array, alignment: Array, count: int) -> Array:
    """``count`` rows of ``pool`` by farthest-point selection (geodesic distance), starting
    from the row whose tool axis is best aligned (ties: the first)."""
    first = int(np.argmax(alignment))
    picked = [first]
    nearest = geodesic(pool, pool[first])
    for _ in range(count - 1):
        k = int(np.argmax(nearest))
        picked.append(k)
        nearest = np.minimum(nearest, geodesic(pool, pool[k]))
    return pool[np.array(picked)]
