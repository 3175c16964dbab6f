"""Kinematic calibration: identify an arm's joint frames, tool offset and base pose from measured
tool poses (the wire's tip GroundTruth sensor or a laser-tracker file). See docs/calibration.md."""
