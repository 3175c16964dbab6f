"""What a fit is asked for and what it returns: :class:`CalibrationOptions` and
:class:`Calibration` (the fit itself is :func:`usar_arm.calibrate.identification.identify`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from usar_arm.calibrate.bounds import Bounds, Correction
from usar_arm.calibrate.changepoint import ALPHA, ChangePoint
from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.parameters import ErrorModel, replace_origin
from usar_arm.calibrate.residuals import Residuals
from usar_arm.core.spatial import Array


@dataclass(frozen=True)
class CalibrationOptions:
    """How to fit (see :mod:`usar_arm.calibrate.identification`).

    Attributes:
        quantisation: ``midpoint``, ``set-membership``, ``likelihood`` or ``auto``.
        max_iterations: Levenberg-Marquardt's cap per stage; a stage that reaches it has not
            converged and the fit is not consistent.
        outlier_sigma: a reading scoring more (sigmas outside its intervals) is an outlier.
        base, tool: whether the base pose and the measured frame's mount are parameters.
        default_sigma_m, default_sigma_rad: noise of a number that states none (m, rad),
            before the noise the readings show replaces it.
        bounds: how far readings and corrections may go (:class:`Bounds`; m, rad).
        change_alpha: false-alarm bound of the moved-mid-run test (:mod:`.changepoint`).
    """

    quantisation: str = "auto"
    max_iterations: int = 50
    outlier_sigma: float = 4.0
    base: bool = True
    tool: bool = True
    default_sigma_m: float = 1e-4
    default_sigma_rad: float = 1e-4
    bounds: Bounds = field(default_factory=Bounds)
    change_alpha: float = ALPHA


@dataclass(frozen=True)
class ParameterEstimate:
    """One identified parameter: its name, value and standard deviation (m or rad)."""

    name: str
    value: float
    std: float


@dataclass(frozen=True)
class Calibration:
    """The result of :func:`~usar_arm.calibrate.identification.identify` (docs/calibration.md).

    Beside the parameters: ``unidentifiable`` (names kept at their URDF values), ``rank``
    (identifiable in these readings) and ``generic_rank`` (in readings at generic
    configurations), ``lost`` (identifiable generically but not in these readings: the
    description is only validated over the configurations sampled), ``consistent`` and
    ``problems`` (why not, in words), ``worst`` / ``rejected`` reading labels, ``change`` (the
    strongest split of the residuals in reading order, ``change_label`` the first reading after
    it), ``converged``, ``corrections`` (each frame's shift and turn) against ``bounds``, and
    ``tool_sigma_m``: the 1-sigma (m) of the measured frame's position from the parameters'
    covariance, median and largest over the fitted configurations.
    """

    parameters: tuple[ParameterEstimate, ...]
    unidentifiable: tuple[str, ...]
    rank: int
    base: Array
    fit: Residuals
    consistent: bool
    worst: tuple[str, ...]
    rejected: tuple[str, ...]
    quantisation: str
    measured_frame: str = ""
    base_guess: Array = field(default_factory=lambda: np.eye(4))
    iterations: int = 0
    vector: Array = field(default_factory=lambda: np.zeros(0))
    tool: bool = True                 # the measured frame's offset was a parameter
    base_fitted: bool = True          # the base pose was a parameter
    qr_rank: int = 0                  # the pivoted QR's rank (equals rank unless ill-posed)
    seconds: float = 0.0              # time the fit took
    generic_rank: int = 0
    lost: tuple[str, ...] = ()
    problems: tuple[str, ...] = ()
    change: ChangePoint | None = None
    change_label: str = ""
    converged: bool = True
    corrections: tuple[Correction, ...] = ()
    bounds: Bounds = field(default_factory=Bounds)
    tool_sigma_m: tuple[float, float] = (0.0, 0.0)
    registered: bool = False          # the base guess was registered from the readings

    def apply(self, urdf: str, tip_joint: str | None = None, fold_base: bool = False) -> str:
        """The calibrated URDF text (joint origins and the measured frame's offset corrected;
        with ``tip_joint``, that fixed joint moved onto the measured frame: see
        :meth:`ErrorModel.apply`).

        ``fold_base``: the readings were given in the description's own base_link, so the
        fitted base pose (``base``: M_from_base_link, M being the nominal base_link) is a
        correction of the description too: it is folded into the origin of the first joint
        below base_link on the way to the measured frame (which the fit merges with it
        anyway), and the written URDF then reproduces the readings without a registration."""
        model = ErrorModel.from_urdf(urdf, self.measured_frame, self.base_fitted, self.tool)
        out = model.apply(urdf, self.vector, tip_joint)
        if not fold_base:
            return out
        first = ErrorModel.from_urdf(out, self.measured_frame, self.base_fitted,
                                     self.tool).path[0]
        return replace_origin(out, first, self.base @ first.origin.matrix())

    def validate(self, urdf: str, measured_frame: str,
                 held_out: Sequence[Measurement]) -> Residuals:
        """Residuals on readings never used for the fit: the nominal ``urdf`` at the base guess
        before, the calibrated URDF (evaluated by Pinocchio) at the fitted base after."""
        from usar_arm.calibrate.validation import validate  # (Pinocchio, loaded when needed)

        return validate(urdf, self.apply(urdf), self.base_guess, self.base, measured_frame,
                        held_out)
