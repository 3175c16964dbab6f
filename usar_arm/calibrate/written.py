"""What a calibration writes, checked as written: the URDF text about to be written, read back
by Pinocchio, against the held-out readings it must reproduce.

The in-memory fit is judged by :mod:`usar_arm.calibrate.validation`; this check reads the text
itself, so a description that differs from the fit (a base correction left out of the file, an
origin printed wrong) is caught before anything is written.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.measurements import Measurement
from usar_arm.core.errors import CalibrationError
from usar_arm.core.spatial import Array, rpy_to_matrix
from usar_arm.planning.kinematics import KinematicModel

AGREEMENT_M = 1e-6
"""How far (m) the written description may be from the fit on a held-out reading: the URDF
prints origins to about 1e-9 m and 1e-9 rad, so anything larger is a different description."""
AGREEMENT_RAD = 1e-6
"""The same for the orientation (rad)."""


@dataclass(frozen=True)
class WrittenCheck:
    """The written URDF's largest distance to the held-out readings (m, rad), through
    ``registration`` (M_from_base_link: identity when the readings are in base_link)."""

    max_m: float
    max_rad: float
    readings: int


def written_check(urdf: str, measured_frame: str, registration: Array,
                  held_out: Sequence[Measurement]) -> WrittenCheck:
    """Read ``urdf`` (the text to be written) with Pinocchio and measure how far its
    ``measured_frame``, put in the readings' frame by ``registration``, is from each held-out
    reading (the joint values at the middle of their printed step)."""
    model = KinematicModel(urdf)
    q = qm.joint_midpoints(held_out)
    worst_m = worst_rad = 0.0
    for m, qk in zip(held_out, q, strict=True):
        pose = registration @ model.frame_pose(qk, measured_frame)
        worst_m = max(worst_m, float(np.linalg.norm(pose[:3, 3] - m.position)))
        if m.rpy is not None:
            c = (np.trace(rpy_to_matrix(m.rpy).T @ pose[:3, :3]) - 1) / 2
            worst_rad = max(worst_rad, float(np.arccos(np.clip(c, -1.0, 1.0))))
    return WrittenCheck(worst_m, worst_rad, len(held_out))


def check_written(written: WrittenCheck, fitted_max_m: float, fitted_max_rad: float) -> None:
    """Raise :class:`CalibrationError` unless the written description reproduces the held-out
    readings as the fit did (its worst distances ``fitted_max_m``, ``fitted_max_rad``)."""
    if (written.max_m > fitted_max_m + AGREEMENT_M
            or written.max_rad > fitted_max_rad + AGREEMENT_RAD):
        raise CalibrationError(
            f"the URDF to be written is {written.max_m * 1e3:.3f} mm / "
            f"{written.max_rad * 1e3:.3f} mrad from the held-out readings where the fit is "
            f"{fitted_max_m * 1e3:.3f} mm / {fitted_max_rad * 1e3:.3f} mrad: it does not "
            "describe what was fitted; nothing written")
