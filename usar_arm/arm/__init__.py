"""The library's front door and the tasks that need an arm: :class:`Arm` (``Arm.connect()`` to
a simulator, ``Arm.from_files()`` offline), the pick-and-place cycle (:mod:`.cycle`) and the
calibration of a live arm through its tip sensor (:mod:`.tour`, :mod:`.tour_calibration`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.arm.cycle import CycleResult as CycleResult
    from usar_arm.arm.cycle import run_cycle as run_cycle
    from usar_arm.arm.facade import Arm as Arm
    from usar_arm.arm.tour_calibration import CalibrationSettings as CalibrationSettings
    from usar_arm.arm.tour_calibration import calibrate_arm as calibrate_arm

__getattr__, __dir__, __all__ = exports(__name__, __file__)
