"""The written-description check: the URDF text about to be written, read back, must reproduce
the held-out readings as the fit did."""

from __future__ import annotations

import numpy as np
import pytest

from tests.calibrate.synthetic import KR60, perturbed, random_q, readings
from usar_arm.calibrate.identification import identify
from usar_arm.calibrate.written import check_written, written_check
from usar_arm.core.errors import CalibrationError
from usar_arm.planning.kinematics import KinematicModel


def test_a_description_without_the_base_correction_is_refused_before_it_is_written() -> None:
    nominal = KinematicModel(KR60)
    truth = perturbed(KR60, 21, metres=1e-3, radians=3e-3)
    data = readings(truth, "tool0", np.eye(4), random_q(nominal, 50, 5), 6, sigma_m=2e-5,
                    sigma_rad=2e-5)
    fit, held = data[:40], data[40:]
    cal = identify(KR60, "tool0", fit, np.eye(4))
    residuals = cal.validate(KR60, "tool0", held).summary()
    folded = written_check(cal.apply(KR60, fold_base=True), "tool0", np.eye(4), held)
    check_written(folded, residuals["max_after_m"], residuals["max_after_rad"])
    assert folded.readings == 10 and folded.max_m < 1e-4
    unfolded = written_check(cal.apply(KR60), "tool0", np.eye(4), held)
    assert unfolded.max_m > 1e-3  # the base correction lives only in memory
    with pytest.raises(CalibrationError, match="does not describe what was fitted"):
        check_written(unfolded, residuals["max_after_m"], residuals["max_after_rad"])
