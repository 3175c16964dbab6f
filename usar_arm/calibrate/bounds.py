"""How much a calibration may change: bounds on the fitted corrections, and on how far the
readings may sit from the nominal description before the fit (:mod:`.plausibility`).

A kinematic calibration corrects a description that is nearly right: a description learnt over
the wire is a few millimetres off, a manufacturer's nominal one rarely more. A fit that needs
centimetres, or tenths of a radian, is not correcting the description but explaining a mistake
(a unit or a frame mixed up, another robot's file), and what it would write is wrong however
well it fits. So the corrections are bounded, per frame: the norm of its shift (m) and the angle
of its turn (rad), each joint frame, the measured frame's mount (``tool``) and the base
separately.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.core.errors import CalibrationError
from usar_arm.core.spatial import Array


@dataclass(frozen=True)
class Bounds:
    """Plausibility bounds (m, rad; options with defaults, see the module).

    Attributes:
        reading_m, reading_rad: the largest distance and angle between a reading and the
            nominal description's pose of the measured frame before the fit (the base put
            where the readings say when the readings' frame is not known).
        joint_m, joint_rad: the largest correction of one joint frame's origin.
        tool_m, tool_rad: the largest correction of the measured frame's mount.
        base_m, base_rad: the largest correction of the base pose from its guess.
    """

    reading_m: float = 0.1
    reading_rad: float = 0.1
    joint_m: float = 0.02
    joint_rad: float = 0.05
    tool_m: float = 0.05
    tool_rad: float = 0.1
    base_m: float = 0.05
    base_rad: float = 0.1

    def __post_init__(self) -> None:
        bad = [k for k, v in asdict(self).items() if not (v > 0 and np.isfinite(v))]
        if bad:
            raise CalibrationError(f"bounds must be positive and finite: {', '.join(bad)}")

    def report(self) -> dict[str, float]:
        """The bounds with their units in the keys (m, rad), for the calibration report."""
        return asdict(self)

    def of(self, kind: str) -> tuple[float, float]:
        """(m, rad) bound of ``kind``: a correction (``joint``, ``tool``, ``base``) or a
        reading's offset before the fit (``reading``)."""
        return getattr(self, f"{kind}_m"), getattr(self, f"{kind}_rad")


@dataclass(frozen=True)
class Correction:
    """One frame's fitted correction: ``frame`` (a joint's name, ``tool`` or ``base``),
    ``kind`` (``joint``, ``tool``, ``base``), its shift (m) and turn (rad)."""

    frame: str
    kind: str
    shift_m: float
    turn_rad: float


def corrections(model: ErrorModel, p: Array) -> tuple[Correction, ...]:
    """Every corrected frame's shift and turn at parameters ``p``."""
    joints, tool, base = model.split(p)
    out = [Correction(name, "joint", float(np.linalg.norm(d[:3])), float(np.linalg.norm(d[3:])))
           for name, d in joints.items()]
    for name, d in (("tool", tool), ("base", base)):
        if d is not None:
            out.append(Correction(name, name, float(np.linalg.norm(d[:3])),
                                  float(np.linalg.norm(d[3:]))))
    return tuple(out)


def largest(found: tuple[Correction, ...]) -> dict[str, dict[str, float | str]]:
    """Per kind, the largest shift and turn and whose they are (for the report)."""
    out: dict[str, dict[str, float | str]] = {}
    for kind in ("joint", "tool", "base"):
        same = [c for c in found if c.kind == kind]
        if same:
            s = max(same, key=lambda c: c.shift_m)
            t = max(same, key=lambda c: c.turn_rad)
            out[kind] = {"shift_m": s.shift_m, "shift_frame": s.frame,
                         "turn_rad": t.turn_rad, "turn_frame": t.frame}
    return out


OPTION = {"joint": "--max-joint-correction", "tool": "--max-tool-correction",
          "base": "--max-base-correction"}
"""The ``usar-arm calibrate`` option that sets each bound (named in the error)."""


def check_corrections(found: tuple[Correction, ...], bounds: Bounds) -> None:
    """Raise :class:`CalibrationError` naming every frame whose correction exceeds its bound:
    the readings need more than a calibration corrects."""
    over = []
    for c in found:
        m, rad = bounds.of(c.kind)
        if c.shift_m > m or c.turn_rad > rad:
            over.append(f"{c.frame} {c.shift_m * 1e3:.1f} mm / {c.turn_rad * 1e3:.1f} mrad "
                        f"(bound {m * 1e3:g} mm / {rad * 1e3:g} mrad, {OPTION[c.kind]})")
    if over:
        raise CalibrationError(
            "the fit needs corrections beyond the plausible: " + "; ".join(over) + ". A "
            "calibration corrects a nearly right description; this much means the readings "
            "belong to another robot, frame or unit (or raise the bound if the description "
            "really is this far off)")
