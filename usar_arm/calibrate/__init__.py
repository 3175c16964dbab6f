"""Kinematic calibration: identify an arm's joint frames, tool offset and base pose from measured
poses of one frame (the wire's tip GroundTruth sensor or a laser-tracker file). See
docs/calibration.md.

measurements (types, file reader) · measurement_writer · parameters (the error model, applied
to URDF text) · quantised, likelihood (interval models) · derivatives, solver (Jacobian, rank,
Levenberg-Marquardt) · result (options, result) · identification (the fit) · bounds, plausibility
(what a calibration may change; readings that cannot belong to the description) · consistency,
changepoint (outliers, a base or tool moved mid-run, convergence, covariance) · residuals ·
validation (held-out blocks, checked via Pinocchio) · observability (pose selection) · report
(JSON report, the write gate) · tour_readings, wire_frames (the wire's readings and frames).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.calibrate.identification import identify as identify
    from usar_arm.calibrate.measurement_writer import write_measurements as write_measurements
    from usar_arm.calibrate.measurements import Measurement as Measurement
    from usar_arm.calibrate.measurements import MeasurementSet as MeasurementSet
    from usar_arm.calibrate.measurements import read_measurements as read_measurements
    from usar_arm.calibrate.observability import select_poses as select_poses
    from usar_arm.calibrate.result import Calibration as Calibration
    from usar_arm.calibrate.result import CalibrationOptions as CalibrationOptions

__getattr__, __dir__, __all__ = exports(__name__, __file__)
