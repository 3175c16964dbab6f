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
