"""How far a model's poses of the measured frame are from measured ones: per reading, before and
after calibration (m, rad)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from usar_arm.calibrate.quantised import Targets, log_many
from usar_arm.core.spatial import Array


@dataclass(frozen=True)
class Residuals:
    """Per reading (``labels``): position distance (m) and rotation angle (rad) between the
    model's pose and the measured one (an interval's middle when quantised), before and after."""

    labels: tuple[str, ...]
    before_m: Array
    before_rad: Array
    after_m: Array
    after_rad: Array

    @staticmethod
    def _max(a: Array) -> float:
        return float(a.max()) if len(a) else 0.0

    @staticmethod
    def _rms(a: Array) -> float:
        return float(np.sqrt(np.mean(a ** 2))) if len(a) else 0.0

    def summary(self) -> dict[str, float]:
        """max and rms of each, in m and rad (stable keys for JSON)."""
        return {f"{stat}_{when}_{unit}": f(getattr(self, f"{when}_{unit}"))
                for when in ("before", "after") for unit in ("m", "rad")
                for stat, f in (("max", self._max), ("rms", self._rms))}

    def rows(self) -> list[dict[str, float | str]]:
        """One row per reading (for JSON and plots)."""
        return [{"label": lb, "before_m": float(a), "before_rad": float(b),
                 "after_m": float(c), "after_rad": float(d)}
                for lb, a, b, c, d in zip(self.labels, self.before_m, self.before_rad,
                                          self.after_m, self.after_rad, strict=True)]


def distances(poses: Array, t: Targets) -> tuple[Array, Array]:
    """(N,) position distances (m) and rotation angles (rad; 0 for position-only readings)."""
    pos = np.linalg.norm(poses[:, :3, 3] - t.mid[:, :3], axis=1)
    rot = np.linalg.norm(log_many(poses[:, :3, :3] @ np.transpose(t.rotations, (0, 2, 1))),
                         axis=1)
    return pos, np.where(t.used[:, 3], rot, 0.0)
