"""Before the fit: do the readings belong to this description at all?

Each reading is compared with the nominal description's pose of the measured frame at its joint
values, the base at its guess, or, when the readings' frame is not known (a tracker in its own
frame), where a rigid registration of the nominal positions onto the measured ones puts it. A
description to be calibrated is a few millimetres off; a reading farther than
:attr:`Bounds.reading_m` / :attr:`Bounds.reading_rad` is a mistake, and the error says which
one it looks like:

* units: the measured positions are a scaled copy of the model's (the scale of a similarity
  registration, e.g. 0.001: metres labelled mm), or the angles are (57x: degrees labelled rad);
* a frame: a constant offset in the measured frame's own axes explains the readings (fitted
  with the base), and the description has a frame rigidly attached there (tool0 is the flange
  turned 90 degrees about y);
* the base: the readings sit off as a whole (the robot or the tracker elsewhere than assumed);
* else: the readings and the description disagree (another robot, joint columns' order).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from usar_arm.calibrate.bounds import Bounds
from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.calibrate.quantised import log_many, rpy_many
from usar_arm.core.errors import CalibrationError
from usar_arm.core.spatial import Array, log_so3, rpy_to_matrix
from usar_arm.urdf.description_reader import parse_urdf

MATCH_M, MATCH_RAD = 0.01, 0.02
"""How close (m, rad) a frame of the description must sit to a constant offset found in the
readings to be named as the frame they were probably taken of."""
WIDE_M = 0.05
"""Spread (rms, m) of the nominal positions needed to judge their scale (units)."""


@dataclass(frozen=True)
class Registration:
    """Where the fit starts: ``base`` (M_from_base_link, 4x4) and whether it was registered
    from the readings (their frame was not known); the largest offsets of a reading from the
    nominal description there (m, rad)."""

    base: Array
    registered: bool
    worst_m: float
    worst_rad: float


def rigid(a: Array, b: Array, scale: bool = False) -> tuple[Array, float]:
    """The transform T (4x4) with b ~ s T a in least squares (Kabsch; Umeyama's scale s when
    ``scale``, else 1), for point sets a, b (N, 3)."""
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    u, s, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    k = float((s * [1.0, 1.0, d]).sum() / max(((a - ca) ** 2).sum(), 1e-300)) if scale else 1.0
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = r, cb - k * r @ ca
    return out, k


def _offsets(base: Array, nominal: Array, pos: Array, rot: Array, has_rot: Array
             ) -> tuple[Array, Array]:
    """Per reading, distance (m) and angle (rad; 0 without orientation) from base * nominal."""
    model = base @ nominal
    dist = np.linalg.norm(model[:, :3, 3] - pos, axis=1)
    ang = np.linalg.norm(log_many(model[:, :3, :3] @ np.transpose(rot, (0, 2, 1))), axis=1)
    return dist, np.where(has_rot, ang, 0.0)


def check_readings(urdf: str, model: ErrorModel, meas: Sequence[Measurement], q: Array,
                   base_guess: Array | None, bounds: Bounds) -> Registration:
    """The base the fit starts from, after checking every reading lies within ``bounds``'
    reading offsets of the nominal description there; else a
    :class:`~usar_arm.core.errors.CalibrationError` naming the worst readings and the likely cause
    (see the module). ``base_guess`` None: the readings' frame is unknown (registered)."""
    nominal = model.poses(np.zeros(model.size), q, np.eye(4))
    pos = np.array([m.position for m in meas], float)
    has_rot = np.array([m.rpy is not None for m in meas])
    rot = np.array([rpy_to_matrix(m.rpy) if m.rpy is not None else np.eye(3) for m in meas])
    base = rigid(nominal[:, :3, 3], pos)[0] if base_guess is None else base_guess
    dist, ang = _offsets(base, nominal, pos, rot, has_rot)
    reg = Registration(base, base_guess is None, float(dist.max()), float(ang.max()))
    if reg.worst_m <= bounds.reading_m and reg.worst_rad <= bounds.reading_rad:
        return reg
    order = np.argsort(-np.maximum(dist / bounds.reading_m, ang / bounds.reading_rad))
    worst = ", ".join(f"{meas[k].label} ({dist[k] * 1e3:.1f} mm, {ang[k] * 1e3:.1f} mrad)"
                      for k in order[:5])
    far = int(((dist > bounds.reading_m) | (ang > bounds.reading_rad)).sum())
    raw = np.array([m.rpy if m.rpy is not None else np.zeros(3) for m in meas], float)
    cause = _cause(urdf, model, nominal, (pos, rot, raw, has_rot), bounds, base_guess)
    raise CalibrationError(
        f"{far} of {len(meas)} readings of {model.measured_frame} are farther from the "
        f"nominal description than {bounds.reading_m * 1e3:g} mm / "
        f"{bounds.reading_rad * 1e3:g} mrad (--max-reading-offset), worst: {worst}. {cause}")


Readings = tuple[Array, Array, Array, Array]
"""Measured positions (N, 3), rotations (N, 3, 3), the rpy numbers as read (N, 3) and which
readings have an orientation (N,)."""


def _cause(urdf: str, model: ErrorModel, nominal: Array, readings: Readings, bounds: Bounds,
           base_guess: Array | None) -> str:
    """What the readings look like (see the module), as a sentence."""
    pos, _, raw, has_rot = readings
    spread = float(np.sqrt(((nominal[:, :3, 3] - nominal[:, :3, 3].mean(0)) ** 2)
                           .sum(1).mean()))
    if spread > WIDE_M:
        base, scale = rigid(nominal[:, :3, 3], pos, scale=True)
        if not 0.5 < scale < 2.0:
            return _unit_sentence("positions", scale, {1e-3: "metres labelled mm?",
                                                       1e3: "millimetres labelled m?"})
    if has_rot.sum() >= 3:
        base = rigid(nominal[:, :3, 3], pos)[0]
        model_rpy = rpy_many(base[:3, :3] @ nominal[has_rot, :3, :3])
        got = np.array([np.ptp(a) for a in raw[has_rot].T])  # as read: unwrapped
        ref = np.array([np.ptp(a) for a in model_rpy.T])
        ratio = float(np.median(got[ref > 0.2] / ref[ref > 0.2])) if (ref > 0.2).any() else 1.0
        if not 0.2 < ratio < 5.0:
            return _unit_sentence("angles", ratio, {np.pi / 180: "radians labelled deg?",
                                                    180 / np.pi: "degrees labelled rad?"})
    return _offset_sentence(urdf, model, nominal, readings, bounds, base_guess)


def _unit_sentence(what: str, scale: float, known: dict[float, str]) -> str:
    ratio = 1 / scale if scale < 1 else scale
    times = f"{ratio:,.0f}x" if ratio >= 10 else f"{ratio:.2g}x"
    size = f"{times} too {'small' if scale < 1 else 'large'}"
    hint = next((h for k, h in known.items() if abs(np.log(scale / k)) < 0.15),
                "another unit than the file states?")
    return f"The measured {what} look {size} against the description's: {hint}"


def _constant_offset(nominal: Array, pos: Array, rot: Array, has_rot: Array
                     ) -> tuple[Array, Array]:
    """The base B and the constant offset X (both 4x4) that best explain measured = B nominal
    X: alternating rigid registrations of the positions with least squares for X's shift,
    then X's rotation as the chordal mean of nominal^-1 B^-1 measured."""
    d: Array = np.zeros(3)
    base = np.eye(4)
    for _ in range(20):
        base = rigid(nominal[:, :3, 3] + nominal[:, :3, :3] @ d, pos)[0]
        a = (base[:3, :3] @ nominal[:, :3, :3]).reshape(-1, 3)
        rhs = (pos - base[:3, 3] - nominal[:, :3, 3] @ base[:3, :3].T).reshape(-1)
        d = np.asarray(np.linalg.lstsq(a, rhs, rcond=None)[0], dtype=np.float64)
    x = np.eye(4)
    x[:3, 3] = d
    if has_rot.any():
        m = np.einsum("nji,jk,nkl->il", nominal[has_rot, :3, :3], base[:3, :3].T, rot[has_rot])
        u, _, vt = np.linalg.svd(m)
        x[:3, :3] = u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt)) or 1.0]) @ vt
    return base, x


def _offset_sentence(urdf: str, model: ErrorModel, nominal: Array, readings: Readings,
                     bounds: Bounds, base_guess: Array | None) -> str:
    pos, rot, _, has_rot = readings
    base, x = _constant_offset(nominal, pos, rot, has_rot)
    dist, ang = _offsets(base, nominal @ x, pos, rot, has_rot)
    if dist.max() > bounds.reading_m or ang.max() > bounds.reading_rad:
        return ("No unit, frame or base offset explains the readings (with the best base and "
                f"a constant offset of the frame they still sit up to {dist.max() * 1e3:.1f} mm "
                f"/ {ang.max() * 1e3:.1f} mrad off): is the URDF this robot's, and are the "
                "joint columns in its order and in the units they state?")
    shift = float(np.linalg.norm(x[:3, 3]))
    w = log_so3(x[:3, :3])
    turn = float(np.linalg.norm(w))
    frame = model.measured_frame
    if shift > bounds.tool_m or turn > bounds.tool_rad:
        axis = w / turn if turn > 0 else w
        match = [f"{n} sits there (--frame {n})" for n in _frames_at(urdf, frame, x)]
        return (f"They sit a constant {shift * 1e3:.1f} mm and {np.degrees(turn):.1f} deg "
                f"about ({axis[0]:.2f}, {axis[1]:.2f}, {axis[2]:.2f}) off {frame} in its own "
                "axes: readings of another frame? "
                + ("; ".join(match) if match else "No frame of the description sits there."))
    if base_guess is not None:
        off = np.linalg.inv(base_guess) @ base
        off_m = float(np.linalg.norm(off[:3, 3]))
        off_rad = float(np.linalg.norm(log_so3(off[:3, :3])))
        if off_m > bounds.base_m or off_rad > bounds.base_rad:
            return (f"They sit off as a whole, as if the base were {off_m * 1e3:.1f} mm / "
                    f"{off_rad * 1e3:.1f} mrad from its guess: the robot or the measuring "
                    "instrument is elsewhere than assumed (readings in another frame?)")
    return ("A small offset of the base and of the frame's mount brings them within the bound: "
            "the description is farther off than the bound allows (raise "
            "--max-reading-offset if it really is)")


def _frames_at(urdf: str, frame: str, x: Array) -> list[str]:
    """Links of ``urdf`` rigidly attached to ``frame`` whose pose in it is within
    :data:`MATCH_M` / :data:`MATCH_RAD` of ``x``."""
    chain, _ = parse_urdf(urdf)
    rng = np.random.default_rng(0)
    qs = [np.zeros(chain.dof), rng.uniform(chain.lower(), chain.upper())]
    out = []
    for link in chain.links:
        if link.name == frame:
            continue
        rel = [np.linalg.inv(chain.frame_pose(frame, q)) @ chain.frame_pose(link.name, q)
               for q in qs]
        if not np.allclose(rel[0], rel[1], atol=1e-9):
            continue
        d = np.linalg.norm(rel[0][:3, 3] - x[:3, 3])
        a = np.linalg.norm(log_so3(rel[0][:3, :3].T @ x[:3, :3]))
        if d <= MATCH_M and a <= MATCH_RAD:
            out.append(link.name)
    return out
