"""What a calibration tour on a server measured, and the file that keeps it.

A tour's readings are the tip sensor's poses as the server printed them (its world: USARSim's
x forward, y right, z down), each with the joint values of the same instant, plus what the fit
needs besides: the platform's pose (the base guess) and the tour's size. The calibrated
description is a function of the as-learnt description and these readings alone, so keeping
them in a file (``<robot>.readings.csv``, the measurements CSV format with a few more header
lines) makes the description reproducible byte for byte: the readings themselves are not,
since the simulator's state at each 10 Hz reading depends on when, in wall-clock time, each
command of the streamed tour arrived.

::

    # frame: KR60ArmTipTruth
    # measured in: the server's world (USARSim: x forward, y right, z down)
    # platform: 0.0 0.0 0.0 0.0 0.0 0.0
    # tour: 14 poses, 35.2 s
    # joint step: 0.0001
    # joint values: rounded
    joint_a1_rad,...,x_m,y_m,z_m,roll_rad,pitch_rad,yaw_rad,step_m,step_rad,sigma_m,sigma_rad,label
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from usar_arm.calibrate.measurement_writer import csv_text
from usar_arm.calibrate.measurements import Measurement, MeasurementSet, read_measurements
from usar_arm.core.errors import FileFormatError
from usar_arm.core.spatial import Array, matrix_to_rpy, rpy_to_matrix, transform

WORLD = "the server's world (USARSim: x forward, y right, z down)"
_TOUR = re.compile(r"^(\d+) poses, ([0-9.]+) s$")


@dataclass(frozen=True)
class TourReadings:
    """A tour's readings (see the module).

    Attributes:
        measurements: the tip sensor's poses in the server's world (m, rad), in time order.
        sensor: the URDF link of the tip sensor (the measured frame).
        joint_names: the URDF's actuated joints, the order of every reading's q.
        platform: the platform's pose in the server's world: x, y, z (m), roll, pitch, yaw
            (rad); the fit's base guess.
        poses: configurations the tour went through. seconds: how long the tour took (s).
        prismatic: which joints are prismatic (their values are metres).
    """

    measurements: tuple[Measurement, ...]
    sensor: str
    joint_names: tuple[str, ...]
    platform: tuple[float, ...]
    poses: int
    seconds: float
    prismatic: tuple[bool, ...]

    @staticmethod
    def platform_numbers(pose: Array) -> tuple[float, ...]:
        """x, y, z, roll, pitch, yaw of a 4x4 pose (what :attr:`platform` keeps)."""
        return tuple(float(v) for v in (*pose[:3, 3], *matrix_to_rpy(pose[:3, :3])))

    def platform_pose(self) -> Array:
        """The platform's 4x4 pose in the server's world."""
        return transform(rpy_to_matrix(self.platform[3:]), self.platform[:3])

    def csv(self) -> str:
        """The file's text (numbers as Python's repr: reading it back gives these readings)."""
        header = (("measured in", WORLD),
                  ("platform", " ".join(repr(v) for v in self.platform)),
                  ("tour", f"{self.poses} poses, {self.seconds!r} s"))
        data = MeasurementSet(self.measurements, self.sensor, joint_names=self.joint_names,
                              header=header)
        return csv_text(data, prismatic=self.prismatic)


LIMIT_SLACK = 1e-2
"""Joint values may lie this far (rad or m) outside the limits: a value printed rounded at a
limit does, and so does a joint read while it tracks its path near a limit (tracking errors
reach a few mrad: a Fanuc tour read joint_a3 at -1.5722 rad, 1.2 mrad past its -1.571 limit).
A readings file of another arm is still refused by its joint names."""


def read_tour(path: str | Path, joint_names: Sequence[str], prismatic: Sequence[bool],
              lower: Array, upper: Array) -> TourReadings:
    """The readings of a tour file for an arm with these joints (errors name the file and
    line: :class:`~usar_arm.core.errors.FileFormatError`)."""
    p = str(path)
    data = read_measurements(p, joint_names, prismatic=prismatic, lower=lower - LIMIT_SLACK,
                             upper=upper + LIMIT_SLACK)
    header = dict(data.header)
    for key in ("measured in", "platform", "tour"):
        if key not in header:
            raise FileFormatError(p, f"no '# {key}: ...' line: not a calibration tour's "
                                  "readings (usar-arm urdf writes them as <robot>.readings.csv)")
    if header["measured in"] != WORLD:
        raise FileFormatError(p, f"'# measured in: {header['measured in']}': expected {WORLD}")
    try:
        platform = tuple(float(v) for v in header["platform"].split())
    except ValueError:
        platform = ()
    if len(platform) != 6 or not all(np.isfinite(platform)):
        raise FileFormatError(p, f"'# platform: {header['platform']}': expected six numbers "
                              "(x y z m, roll pitch yaw rad)")
    tour = _TOUR.match(header["tour"])
    if tour is None:
        raise FileFormatError(p, f"'# tour: {header['tour']}': expected 'N poses, S s'")
    return TourReadings(data.measurements, data.frame, tuple(joint_names), platform,
                        int(tour.group(1)), float(tour.group(2)), tuple(prismatic))
