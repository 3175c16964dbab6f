"""The calibration report: a JSON-ready dictionary with stable keys (parameters and their
standard deviations, the unidentifiable ones, residuals before/after on the fit and on the
held-out readings, consistency), and the check that decides whether a fit may be written."""

from __future__ import annotations

from typing import Any

from usar_arm.calibrate.identify import Calibration
from usar_arm.calibrate.residuals import Residuals
from usar_arm.errors import CalibrationError


def calibration_dict(cal: Calibration, validation: Residuals | None,
                     notes: tuple[str, ...] = ()) -> dict[str, Any]:
    """The report (units: m and rad)."""
    return {
        "measured_frame": cal.measured_frame,
        "quantisation": cal.quantisation,
        "consistent": cal.consistent,
        "rank": cal.rank,
        "parameters": [{"name": p.name, "value": p.value, "std": p.std}
                       for p in cal.parameters],
        "unidentifiable": list(cal.unidentifiable),
        "base": cal.base.tolist(),
        "rejected": list(cal.rejected),
        "worst": list(cal.worst),
        "iterations": cal.iterations,
        "seconds": cal.seconds,
        "fit": {"summary": cal.fit.summary(), "readings": cal.fit.rows()},
        "validation": None if validation is None else {
            "summary": validation.summary(), "readings": validation.rows()},
        "notes": list(notes),
    }


def check_validated(cal: Calibration, validation: Residuals) -> None:
    """Raise :class:`CalibrationError` unless the fit is consistent and the held-out readings
    are no worse after than before (rms of position and of rotation)."""
    if not cal.consistent:
        raise CalibrationError("the readings contradict the model (consistent: false); worst "
                               f"readings: {', '.join(cal.worst)}")
    s = validation.summary()
    if len(validation.labels) == 0:
        raise CalibrationError("no held-out readings to validate the fit on")
    if s["rms_after_m"] > s["rms_before_m"] or s["rms_after_rad"] > s["rms_before_rad"] * 1.0001:
        raise CalibrationError(
            f"the fit does not hold on the held-out readings (rms {s['rms_before_m'] * 1e3:.3f} "
            f"mm before, {s['rms_after_m'] * 1e3:.3f} mm after)")
