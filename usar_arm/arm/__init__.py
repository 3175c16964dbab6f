"""The library's front door and the tasks that need an arm: :class:`Arm` (``Arm.connect()`` to
a simulator, ``Arm.from_files()`` offline), the pick-and-place cycle (:mod:`.cycle`) and the
calibration of a live arm through its tip sensor (:mod:`.tour`, :mod:`.tour_calibration`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from usar_arm.arm.facade import Arm

__all__ = ["Arm"]


def __getattr__(name: str) -> Any:
    if name == "Arm":
        from usar_arm.arm.facade import Arm

        return Arm
    raise AttributeError(f"module 'usar_arm.arm' has no attribute {name!r}")
