"""What both modes of ``usar-arm calibrate`` (and ``usar-arm urdf``'s default calibration) say
about a fit, and the fit's options from the arguments: shared by :mod:`.calibrate_cmd` (FILE
mode) and :mod:`.calibrate_robot` (ROBOT mode)."""

from __future__ import annotations

import argparse

from usar_arm.calibrate.bounds import Bounds
from usar_arm.calibrate.identification import Calibration, CalibrationOptions
from usar_arm.calibrate.report import compact_names
from usar_arm.cli.common import err

BOUND_OPTIONS = (("reading", "--max-reading-offset",
                  "how far a reading may sit from the nominal description before the fit"),
                 ("joint", "--max-joint-correction", "the largest correction of a joint frame"),
                 ("tool", "--max-tool-correction",
                  "the largest correction of the measured frame's mount"),
                 ("base", "--max-base-correction",
                  "the largest correction of the base from its guess"))
"""(kind, option, what it bounds) of each bound of :class:`Bounds`."""


def calibration_options(args: argparse.Namespace) -> CalibrationOptions:
    """The fit's options from the arguments (bounds in SI units)."""
    values = {f"{kind}_{unit}": float(v) for kind, flag, _ in BOUND_OPTIONS
              for unit, v in zip(("m", "rad"), getattr(args, flag[2:].replace("-", "_")),
                                 strict=True)}
    return CalibrationOptions(quantisation=args.quantisation, bounds=Bounds(**values))


def milli(x: float) -> str:
    """``x`` (m or rad) in mm or mrad, to the micrometre."""
    return f"{x * 1e3:.3f}"


def residual_line(label: str, summary: dict[str, float], note: str = "") -> str:
    """The largest residuals before -> after (mm, mrad) of a :meth:`Residuals.summary`."""
    return (f"  {label:<10} max {milli(summary['max_before_m'])} -> "
            f"{milli(summary['max_after_m'])} mm, {milli(summary['max_before_rad'])} -> "
            f"{milli(summary['max_after_rad'])} mrad{note}")


def identifiability_line(cal: Calibration) -> str:
    """What the fit could identify, by name."""
    return (f"  rank {cal.rank} of {cal.generic_rank} generically identifiable; "
            f"{len(cal.unidentifiable)} unidentifiable, kept as in the URDF: "
            f"{compact_names(cal.unidentifiable)}")


def warn_lost(cal: Calibration) -> None:
    """A warning on stderr when these readings identify less than readings at generic
    configurations would: the description then holds only near the configurations sampled."""
    if cal.lost:
        err(f"warning: these readings cannot identify {compact_names(cal.lost)} (readings at "
            "generic configurations would): the description is only validated over the "
            "configurations sampled (the held-out check)")


def tool_point_line(cal: Calibration, source: str) -> str:
    """How well the tool point is fixed, and by what."""
    med, worst = cal.tool_sigma_m
    return (f"  tool point {cal.measured_frame}: 1-sigma {milli(med)} mm median, "
            f"{milli(worst)} mm max over the fitted configurations; {source}")
