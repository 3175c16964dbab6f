"""The calibration report: a JSON-ready dictionary with stable keys (parameters and their
standard deviations, the unidentifiable ones, residuals before/after on the fit and on the
held-out readings, consistency), and the check that decides whether a fit may be written."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from usar_arm.calibrate.bounds import largest
from usar_arm.calibrate.residuals import Residuals
from usar_arm.calibrate.result import Calibration
from usar_arm.core.errors import CalibrationError
from usar_arm.core.precision import with_precision


def compact_names(names: Sequence[str]) -> str:
    """Parameter names grouped by frame, e.g. ``joint_a1.origin.{x,y,z}, base.{x,yaw}``."""
    groups: dict[str, list[str]] = {}
    for name in names:
        head, _, axis = name.rpartition(".")
        groups.setdefault(head, []).append(axis)
    return ", ".join(f"{head}.{axes[0]}" if len(axes) == 1 else f"{head}.{{{','.join(axes)}}}"
                     for head, axes in groups.items())


def calibration_dict(cal: Calibration, validation: Residuals | None,
                     notes: tuple[str, ...] = (), tool_point: str = "") -> dict[str, Any]:
    """The report (units: m and rad, in the keys; numbers with the precision they mean, see
    :mod:`usar_arm.core.precision`; the fit's duration, which varies from run to run, is left
    out). ``tool_point``: which source fixes the tool point."""
    change = cal.change
    return with_precision({
        "measured_frame": cal.measured_frame,
        "quantisation": cal.quantisation,
        "consistent": cal.consistent,
        "problems": list(cal.problems),
        "converged": cal.converged,
        "rank": cal.rank,
        "generic_rank": cal.generic_rank,
        "lost": list(cal.lost),
        "parameters": [{"name": p.name, "value": p.value, "std": p.std}
                       for p in cal.parameters],
        "unidentifiable": list(cal.unidentifiable),
        "base": cal.base.tolist(),
        "rejected": list(cal.rejected),
        "worst": list(cal.worst),
        "iterations": cal.iterations,
        "change_point": None if change is None else {
            "first_reading_after": cal.change_label, "group": change.group,
            "shift": list(change.shift), "statistic": change.statistic,
            "threshold": change.threshold, "detected": change.detected},
        "bounds": cal.bounds.report(),
        "largest_corrections": largest(cal.corrections),
        "tool_point": {"source": tool_point, "sigma_m_median": cal.tool_sigma_m[0],
                       "sigma_m_max": cal.tool_sigma_m[1]},
        "fit": {"summary": cal.fit.summary(), "readings": cal.fit.rows()},
        "validation": None if validation is None else {
            "summary": validation.summary(), "readings": validation.rows()},
        "notes": list(notes),
    })


def check_validated(cal: Calibration, validation: Residuals) -> None:
    """Raise :class:`CalibrationError` unless the fit is consistent and the held-out readings
    are no worse after than before (rms of position and of rotation)."""
    if not cal.consistent:
        raise CalibrationError("the readings contradict the model (consistent: false): "
                               f"{'; '.join(cal.problems)}; worst readings: "
                               f"{', '.join(cal.worst)}")
    s = validation.summary()
    if len(validation.labels) == 0:
        raise CalibrationError("no held-out readings to validate the fit on")
    if s["rms_after_m"] > s["rms_before_m"] or s["rms_after_rad"] > s["rms_before_rad"] * 1.0001:
        raise CalibrationError(
            f"the fit does not hold on the held-out readings (rms {s['rms_before_m'] * 1e3:.3f} "
            f"mm before, {s['rms_after_m'] * 1e3:.3f} mm after)")
