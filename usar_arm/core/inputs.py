"""User input turned into arrays: numbers, joint vectors and goal poses, checked once, with the
errors users see (:class:`~usar_arm.core.errors.InvalidInputError` naming what was wrong and
what was expected). Metres and radians."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from usar_arm.core.errors import InvalidInputError
from usar_arm.core.spatial import Array

RIGID_TOLERANCE = 1e-6
"""Largest |R^T R - I| entry of a goal pose's rotation (and error of its bottom row)."""


def numbers(values: Any, what: str) -> Array:
    """``values`` as a float array.

    Raises:
        InvalidInputError: "{what} must be numbers" when they are not.
    """
    try:
        return np.asarray(values, float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{what} must be numbers, got {values!r}") from None


def joint_vector(values: Any, names: Sequence[str], what: str, *, noun: str = "joint values",
                 named: bool = True) -> Array:
    """``values`` as one value per joint of ``names`` (rad or m).

    Raises:
        InvalidInputError: not numbers, or "{what} needs {n} {noun} ({names}), got {count}"
            (the names listed when ``named``).
    """
    q = numbers(values, what)
    if q.shape != (len(names),):
        listed = f" ({', '.join(names)})" if named else ""
        raise InvalidInputError(f"{what} needs {len(names)} {noun}{listed}, got {q.size}")
    return q


def rigid_defects(t: Array) -> tuple[float, float, float]:
    """How far a 4x4 matrix is from a rigid transform: the largest |R^T R - I| entry, det R,
    and the largest error of its bottom row against (0, 0, 0, 1)."""
    rot = t[:3, :3]
    off = float(np.max(np.abs(rot.T @ rot - np.eye(3))))
    return off, float(np.linalg.det(rot)), float(np.max(np.abs(t[3] - (0.0, 0.0, 0.0, 1.0))))


def check_pose(pose: Any) -> Array:
    """``pose`` as a 4x4 float array, checked to be a finite rigid transform (m).

    Raises:
        InvalidInputError: not 4x4, NaN or infinite entries, or no rotation (not orthonormal,
            a reflection) or a bottom row other than (0, 0, 0, 1).
    """
    t = numbers(pose, "the goal pose")
    if t.shape != (4, 4):
        raise InvalidInputError(f"a goal pose is a 4x4 homogeneous transform (m), got an array "
                                f"of shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise InvalidInputError("the goal pose contains NaN or infinite values")
    off, det, row = rigid_defects(t)
    if off > RIGID_TOLERANCE or det < 0:
        raise InvalidInputError(f"the goal pose's rotation is not a rotation matrix "
                                f"(|R^T R - I| up to {off:.2g}, det {det:.4f}; expected "
                                f"orthonormal, det +1)")
    if row > RIGID_TOLERANCE:
        raise InvalidInputError(f"the goal pose's bottom row is {t[3].tolist()}, expected "
                                "[0, 0, 0, 1]")
    return t
