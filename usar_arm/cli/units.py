"""Poses as users type them, converted at the CLI edge to SI 4x4 transforms (and back).

``m-rad``: X Y Z in m, ROLL PITCH YAW in rad (fixed axes, R = Rz(yaw) Ry(pitch) Rx(roll)).
``mm-deg``: the same in mm and degrees.
``kuka``: as on a KUKA pendant: X Y Z in mm and A B C in degrees (A about Z, then B about Y,
then C about X), of KUKA's tool frame, whose X axis points out of the flange; it is converted to
the pose of tool0 (z out of the flange) with the robot's own flange -> tool0 rotation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from usar_arm.core.errors import InvalidInputError
from usar_arm.core.spatial import Array, rpy_to_matrix, transform

UNITS = ("m-rad", "mm-deg", "kuka")


def pose_from_args(values: Sequence[float], units: str, tool0_in_flange: Array) -> Array:
    """The 4x4 pose of tool0 in base_link from six numbers in ``units``."""
    if len(values) != 6:
        raise InvalidInputError(f"a pose needs 6 numbers (X Y Z and three angles), got "
                                f"{len(values)}")
    if not all(math.isfinite(v) for v in values):
        raise InvalidInputError(f"pose numbers must be finite, got {list(values)}")
    x, y, z, a, b, c = (float(v) for v in values)
    if units == "m-rad":
        return transform(rpy_to_matrix((a, b, c)), (x, y, z))
    if units == "mm-deg":
        return transform(rpy_to_matrix(np.radians([a, b, c])), np.array([x, y, z]) / 1000)
    if units == "kuka":
        flange = transform(rpy_to_matrix(np.radians([c, b, a])), np.array([x, y, z]) / 1000)
        return flange @ tool0_in_flange
    raise InvalidInputError(f"--units must be one of {', '.join(UNITS)}, got '{units}'")
