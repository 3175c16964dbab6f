"""The measurement behind CalibrationOptions(quantisation="auto"): on synthetic readings of the
tip sensor printed to 1 mm / 1 mrad, the model "auto" stands for is the most accurate one."""

from __future__ import annotations

import pytest

from tests.calibrate.synthetic import KR60, perturbed, random_q, readings, tool_errors
from usar_arm.calibrate.identification import AUTO_MODEL, CalibrationOptions, identify
from usar_arm.calibrate.quantised import MODELS
from usar_arm.core.spatial import FLIP_X, transform, transform_from_xyz_rpy
from usar_arm.planning.kinematics import KinematicModel

FRAME = "KR60ArmTipTruth"
NOMINAL = KinematicModel(KR60)


def _errors(seed: int, count: int, kind: str) -> tuple[float, float]:
    truth = perturbed(KR60, seed)
    base = transform(FLIP_X) @ transform_from_xyz_rpy([0.3, 0.2, 0.0015], [0.003, -0.002, 0.004])
    guess = transform(FLIP_X) @ transform_from_xyz_rpy([0.3, 0.2, 0.0], [0.0, 0.0, 0.0])
    data = readings(truth, FRAME, base, random_q(NOMINAL, count, 10 + seed), 3,
                    step_m=1e-3, step_rad=1e-3)
    cal = identify(KR60, FRAME, data, guess, CalibrationOptions(quantisation=kind))
    return tool_errors(truth, base, cal.apply(KR60), cal.base, FRAME,
                       random_q(NOMINAL, 300, 5))


def _compare(seeds: list[int], count: int) -> None:
    others = [m for m in MODELS if m != AUTO_MODEL]
    for seed in seeds:
        auto = _errors(seed, count, AUTO_MODEL)
        for other in others:
            alt = _errors(seed, count, other)
            assert auto[0] <= alt[0] and auto[1] <= alt[1], (seed, other, auto, alt)


def test_auto_is_the_more_accurate_model_on_200_truncated_readings() -> None:
    _compare([1], 200)


@pytest.mark.slow
def test_auto_is_the_more_accurate_model_over_seeds_and_counts() -> None:
    for count in (200, 500):
        _compare([1, 2, 3], count)
