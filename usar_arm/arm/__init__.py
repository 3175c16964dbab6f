"""The library's front door and the tasks that need an arm: :class:`Arm` (``Arm.connect()`` to
a simulator, ``Arm.from_files()`` offline), the pick-and-place cycle (:mod:`.cycle`) and the
calibration of a live arm through its tip sensor (:mod:`.tour`, :mod:`.tour_calibration`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.arm.cycle import CycleResult, run_cycle
    from usar_arm.arm.facade import Arm
    from usar_arm.arm.tour_calibration import CalibrationSettings, calibrate_arm

_HOMES = {
    "cycle": ("CycleResult", "run_cycle"),
    "facade": ("Arm",),
    "tour_calibration": ("CalibrationSettings", "calibrate_arm"),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["Arm", "CalibrationSettings", "CycleResult", "calibrate_arm", "run_cycle"]

__getattr__ = exports(__name__, _HOMES)
