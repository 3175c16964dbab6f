"""How close the real tool came to its goal after a motion: one typed record instead of a dict
whose string keys were spelled out in five modules."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from usar_arm.core.spatial import Array, pose_error


@dataclass(frozen=True)
class TipCorrectionFigures:
    """What a tip correction did (see :func:`~usar_arm.control.tip_correction.correct_tip`).

    Attributes:
        before_m, before_rad: tool0's measured error before the correction (m, rad).
        readings: sensor readings it took.
        bias_m, bias_rad: the size of the estimated model-to-sensor bias (m, rad).
        bias_consistent: the readings agreed on one bias within their printed steps.
        rounds: correction rounds; verified: the final pose was re-measured within tolerance.
    """

    before_m: float
    before_rad: float
    readings: int
    bias_m: float
    bias_rad: float
    bias_consistent: bool
    rounds: int
    verified: bool


@dataclass(frozen=True)
class ToolAccuracy:
    """tool0's error against the goal pose at the end of a motion.

    Attributes:
        source: what measured it (the tip sensor, or forward kinematics of the joint readings).
        error_m, error_rad: that measurement's position (m) and rotation (rad) error.
        sensor_step_m: the step the tip sensor printed positions with (m), when it measured.
        correction: the tip correction's figures, when one ran.
        true_error_m, true_error_rad: the error by the embedded simulator's own truth, when the
            simulator runs in this process (None otherwise).
    """

    source: str
    error_m: float
    error_rad: float
    sensor_step_m: float | None = None
    correction: TipCorrectionFigures | None = None
    true_error_m: float | None = None
    true_error_rad: float | None = None

    def as_json(self) -> dict[str, Any]:
        """The flat keys reports print (``tip_error_m``, ``true_tip_error_m``, ...)."""
        out: dict[str, Any] = {"tip_source": self.source, "tip_error_m": self.error_m,
                               "tip_error_rad": self.error_rad}
        if self.sensor_step_m is not None:
            out["tip_sensor_step_m"] = self.sensor_step_m
        fix = self.correction
        if fix is not None:
            out.update(tip_error_before_correction_m=fix.before_m,
                       tip_error_before_correction_rad=fix.before_rad,
                       tip_readings=fix.readings, tip_bias_m=fix.bias_m,
                       tip_bias_rad=fix.bias_rad, tip_bias_consistent=fix.bias_consistent,
                       tip_correction_rounds=fix.rounds, tip_verified=fix.verified)
        if self.true_error_m is not None:
            out.update(true_tip_error_m=self.true_error_m, true_tip_error_rad=self.true_error_rad)
        return out


def sensor_accuracy(source: str, target: Array, measured: Array, step_m: float
                    ) -> ToolAccuracy:
    """tool0's error when a sensor ``source`` measured it at pose ``measured`` (4x4, m)
    against ``target``, printing positions with ``step_m`` (m)."""
    _, error_m, error_rad = pose_error(target, measured)
    return ToolAccuracy(source, error_m, error_rad, sensor_step_m=step_m)
