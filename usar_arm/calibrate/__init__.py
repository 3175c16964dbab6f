"""Kinematic calibration: identify an arm's joint frames, tool offset and base pose from measured
poses of one frame (the wire's tip GroundTruth sensor or a laser-tracker file). See
docs/calibration.md.

measurements (types, file reader) · measurement_writer · parameters (the error model, applied
to URDF text) · quantised, likelihood (interval models) · derivatives, solver (Jacobian, rank,
Levenberg-Marquardt) · result (options, result) · identify (the fit) · bounds, plausibility
(what a calibration may change; readings that cannot belong to the description) · consistency,
changepoint (outliers, a base or tool moved mid-run, convergence, covariance) · residuals ·
validation (held-out blocks, checked via Pinocchio) · observability (pose selection) · report
(JSON report, the write gate) · tour_readings, wire_frames (the wire's readings and frames).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.calibrate.identify import identify
    from usar_arm.calibrate.measurement_writer import write_measurements
    from usar_arm.calibrate.measurements import Measurement, MeasurementSet, read_measurements
    from usar_arm.calibrate.observability import select_poses
    from usar_arm.calibrate.result import Calibration, CalibrationOptions

_HOMES = {
    "identify": ("identify",),
    "measurement_writer": ("write_measurements",),
    "measurements": ("Measurement", "MeasurementSet", "read_measurements"),
    "observability": ("select_poses",),
    "result": ("Calibration", "CalibrationOptions"),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["Calibration", "CalibrationOptions", "Measurement", "MeasurementSet", "identify",
           "read_measurements", "select_poses", "write_measurements"]

__getattr__ = exports(__name__, _HOMES)
