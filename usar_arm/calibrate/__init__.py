"""Kinematic calibration: identify an arm's joint frames, tool offset and base pose from measured
poses of one frame (the wire's tip GroundTruth sensor or a laser-tracker file). See
docs/calibration.md.

measurements (types, file reader) · measurement_writer · parameters (the error model, applied
to URDF text) · quantised (interval models) · solver (Jacobian, rank, Levenberg-Marquardt) ·
identify (options, result, the fit) · residuals · validation (held-out check via Pinocchio) ·
observability (pose selection, dithering) · report (JSON report, the write gate).
"""
