"""How numbers are written on the USARSim wire.

UDK prints numbers in three ways (docs/protocol.md section 2):

* ``UnitsConverter.FloatString(v, p)``: exactly ``p`` decimals, the fraction **truncated**, computed
  in 32-bit floats. Actuator GEO locations and GroundTruth poses use ``p = 3``.
* raw floats concatenated into strings (Time, ASTA Value, CONF MaxTorque/MinValue/MaxValue): we
  print these with 4 decimals, rounded, as the reference advises.
* raw vectors (link GEO orientations, ``Tip``): 2 decimals, rounded.

``NumberStyle`` bundles one choice for each kind. ``UDK`` reproduces the engine, ``FULL``
prints every number with enough digits to round-trip a float64 (an extension for users who want the
learnt model to equal the simulator's exactly).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

Vector3 = tuple[float, float, float]

_F32_SAFE = 3.0e38
"""Below this magnitude a float64 always converts to a finite float32."""


def udk_float_string(value: float, precision: int) -> str:
    """UnrealScript ``UnitsConverter.FloatString(value, precision)``, in float32 arithmetic.

    A value that is not finite in float32 (NaN, +-inf, or beyond +-3.4e38 m) has no UDK form
    (UnrealScript's ``int()`` of it is undefined): it prints as ``nan``, ``inf`` or ``-inf``,
    which :func:`usar_arm.usarsim.codec.parse_line` refuses, instead of failing the sender.

    >>> udk_float_string(-1.0049, 3)
    '-1.004'
    >>> udk_float_string(1e39, 3)
    'inf'
    """
    f32 = np.float32
    if math.isfinite(value) and abs(value) < _F32_SAFE:  # the common case, without errstate
        v = f32(value)
    else:
        with np.errstate(over="ignore", invalid="ignore"):
            v = f32(value)
        if not np.isfinite(v):
            return str(float(v))
    sign = ""
    if v < 0:
        sign = "-"
        v = f32(v * f32(-1.0))
    int_part = int(v)
    frac = f32(v - f32(int_part))
    digits = int(f32(frac * f32(10.0**precision)))
    return f"{sign}{int_part}.{str(digits).rjust(precision, '0')}"


def round_decimals(value: float, decimals: int) -> str:
    """A float printed with a fixed number of decimals, rounded (printf ``%.Nf``)."""
    text = f"{value:.{decimals}f}"
    if text.startswith("-") and float(text) == 0.0:
        text = text[1:]  # no "-0.00"
    return text


def full_float(value: float) -> str:
    """The shortest positional decimal that reads back as exactly ``value`` (float64)."""
    text = np.format_float_positional(np.float64(value), unique=True, trim="0")
    return text


def join_vector(values: Sequence[float], fmt: Callable[[float], str]) -> str:
    """``x,y,z`` with no spaces, each component printed by ``fmt``."""
    return ",".join(fmt(float(v)) for v in values)


@dataclass(frozen=True)
class NumberStyle:
    """How each kind of number is printed.

    Attributes:
        name: ``"udk"`` or ``"full"``.
        scalar_decimals: decimals of raw scalars (Time, Value, MaxTorque...), or None for full.
        fixed_precision: ``p`` of FloatString fields (GEO locations, GroundTruth), or None for full.
        vector_decimals: decimals of raw vectors (link orientations, Tip), or None for full.
    """

    name: str
    scalar_decimals: int | None
    fixed_precision: int | None
    vector_decimals: int | None

    def scalar(self, value: float) -> str:
        """A raw engine float (Time, ASTA Value, CONF limits)."""
        if self.scalar_decimals is None:
            return full_float(value)
        return round_decimals(value, self.scalar_decimals)

    def fixed(self, value: float) -> str:
        """A FloatString(p) number (truncated in float32)."""
        if self.fixed_precision is None:
            return full_float(value)
        return udk_float_string(value, self.fixed_precision)

    def fixed_at(self, value: float, precision: int) -> str:
        """A FloatString(value, precision) number, for fields UDK prints with an explicit
        precision (scanner ranges: 2; Resolution, FOV, vehicle CONF/GEO: the default 4)."""
        if self.fixed_precision is None:
            return full_float(value)
        return udk_float_string(value, precision)

    def fixed_vector(self, values: Sequence[float]) -> str:
        """A vector of FloatString(p) numbers."""
        return join_vector(values, self.fixed)

    def raw_vector(self, values: Sequence[float]) -> str:
        """A vector concatenated raw into a string by the engine."""
        if self.vector_decimals is None:
            return join_vector(values, full_float)
        decimals = self.vector_decimals
        return join_vector(values, lambda v: round_decimals(v, decimals))

    def quantize_fixed(self, value: float) -> float:
        """The value a client reads back after ``fixed`` printing."""
        return float(self.fixed(value))

    def quantize_raw(self, value: float) -> float:
        """The value a client reads back after ``raw_vector`` printing of one component."""
        return float(self.raw_vector([value]))

    def quantize_scalar(self, value: float) -> float:
        """The value a client reads back after ``scalar`` printing."""
        return float(self.scalar(value))


ROUNDED_SCALARS = True
"""Raw engine floats (ASTA Value, Time, CONF limits) are printed rounded to their step (the
engine's float formatting); FloatString numbers (GroundTruth poses, actuator GEO locations) are
truncated toward zero. A printed raw scalar v with step s stands for [v - s/2, v + s/2]."""

UDK = NumberStyle("udk", scalar_decimals=4, fixed_precision=3, vector_decimals=2)
FULL = NumberStyle("full", scalar_decimals=None, fixed_precision=None, vector_decimals=None)

STYLES: dict[str, NumberStyle] = {"udk": UDK, "full": FULL}


def printed_resolution(line: str, key: str) -> float:
    """The finest step (10^-decimals) of the numbers printed in ``{key ...}`` blocks of a line,
    or 0.0 for full precision: UDK never prints more than 4 decimals, so more (or an exponent)
    means a full-precision server.

    >>> printed_resolution("GEO {Location 0.070,0.010,-0.413} {Orientation 3.14,0.00,0.00}",
    ...                    "Orientation")
    0.01
    """
    decimals = 0
    for block in re.findall(r"\{" + key + r"\s+([^}]*)\}", line, flags=re.IGNORECASE):
        for number in block.split(","):
            text = number.strip().lower()
            if "e" in text:
                return 0.0  # exponent notation: full precision
            if "." in text:
                decimals = max(decimals, len(text.split(".")[1]))
    if decimals > 4:
        return 0.0
    return 10.0 ** -decimals


_BLOCK = re.compile(r"\{(\w+)\s+([^}]*)\}")


def printed_steps(line: str) -> dict[str, float]:
    """:func:`printed_resolution` of every block key of ``line`` at once, keys lower-cased.

    >>> printed_steps("SEN {Time 1.50} {Name Tip} {Location 0.070,0.010,-0.413}")
    {'time': 0.01, 'name': 1.0, 'location': 0.001}
    """
    decimals: dict[str, int] = {}
    for key, block in _BLOCK.findall(line):
        key = key.lower()
        best = decimals.get(key, 0)
        for number in block.split(","):
            text = number.strip().lower()
            if "e" in text and any(c.isdigit() for c in text):
                best = 99  # exponent notation: full precision
            elif "." in text:
                best = max(best, len(text.split(".")[1]))
        decimals[key] = best
    return {key: (0.0 if d > 4 else 10.0 ** -d) for key, d in decimals.items()}


def truncated_midpoint(values: Sequence[float], step: float) -> list[float]:
    """Best estimates of values printed truncated (toward zero) to ``step``: the middle of the
    interval each printed value stands for (a printed 0 stays 0)."""
    if step <= 0:
        return [float(v) for v in values]
    return [float(v) + (0.0 if v == 0 else math.copysign(step / 2, v)) for v in values]
