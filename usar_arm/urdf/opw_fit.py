"""Is an arm ortho-parallel with a spherical wrist (OPW), and with which parameters?

The OPW parameters (Brandstötter, Angerer, Hofbaur 2014, as the ``opw_kinematics`` library and
Tesseract's ``OPWInvKin`` use them) describe an arm whose zero pose points straight up along the
z axis of its base frame: c1 is the height of joint 2, a1 its offset along x, b the lateral
offset of the wrist centre along y, c2 the upper arm, a2 and c3 the elbow offset and forearm
(joint 3 -> wrist centre), c4 the wrist centre -> tool. ``offsets`` bring that zero to the arm's
own, ``sign_corrections`` flip joints that turn the other way:
``q_opw = q * sign - offset``.

:func:`fit_opw` reads those parameters from the arm's own axes at its zero configuration, then
*measures* how well they reproduce the arm: OPW forward kinematics (:func:`opw_forward`)
against the chain's forward kinematics at random configurations inside the limits. Only that
measured deviation says whether the arm is OPW; the structural checks only decide whether
parameters can be read at all. Lengths in m, angles in rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usar_arm.core.model import JointType, KinematicChain
from usar_arm.core.spatial import Array, Vector, invert


class NotOpwError(ValueError):
    """No OPW parameters can be read from the arm; ``reason`` says which condition fails."""

    def __init__(self, reason: str):
        self.reason = reason
        super().__init__(f"not an OPW arm: {reason}")


@dataclass(frozen=True)
class OpwLengths:
    """The seven lengths (m) of an ortho-parallel arm: c1 shoulder height, a1 shoulder offset,
    b lateral offset, c2 upper arm, a2 elbow offset, c3 forearm (elbow -> wrist centre), c4
    wrist centre -> flange."""

    a1: float
    a2: float
    b: float
    c1: float
    c2: float
    c3: float
    c4: float


@dataclass(frozen=True)
class OpwParameters(OpwLengths):
    """The OPW parameters (m, rad) in ``opw_kinematics``' convention: the lengths, and each
    joint's offset (rad) and sign."""

    offsets: tuple[float, float, float, float, float, float]
    sign_corrections: tuple[int, int, int, int, int, int]


@dataclass(frozen=True)
class OpwFit:
    """OPW parameters of an arm and how far they are from it.

    Attributes:
        parameters: the OPW parameters.
        base: 4x4 pose of the OPW base frame in the chain's root frame (on joint 1's axis).
        tip: link whose frame is the OPW tool frame.
        joints: the six joints, base to tip.
        wrist_gap_m: the largest distance between two of the three wrist axes (m; the
            length of their common perpendicular, or their spacing when parallel): 0 for a
            spherical wrist.
        wrist_gap_joints: the two joints whose axes are that far apart.
        position_error_m: largest tip position difference OPW vs chain over the samples (m).
        rotation_error_rad: largest tip rotation difference over the samples (rad).
        samples: configurations compared (uniform inside the joint limits).
    """

    parameters: OpwParameters
    base: Array
    tip: str
    joints: tuple[str, ...]
    wrist_gap_m: float
    wrist_gap_joints: tuple[str, str]
    position_error_m: float
    rotation_error_rad: float
    samples: int

    def within(self, position_m: float, rotation_rad: float) -> bool:
        """True when the measured deviation is within both tolerances."""
        return self.position_error_m <= position_m and self.rotation_error_rad <= rotation_rad


def _rz(t: float) -> Array:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _ry(t: float) -> Array:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _wrap(t: float) -> float:
    w = (t + math.pi) % (2.0 * math.pi) - math.pi
    return math.pi if abs(w + math.pi) < 1e-15 else w


def opw_forward(p: OpwParameters, q: Vector) -> Array:
    """4x4 pose of the OPW tool frame in the OPW base frame at joint values ``q`` (rad)."""
    t = [float(q[i]) * p.sign_corrections[i] - p.offsets[i] for i in range(6)]
    psi3 = math.atan2(p.a2, p.c3)
    k = math.hypot(p.a2, p.c3)
    cx1 = p.c2 * math.sin(t[1]) + k * math.sin(t[1] + t[2] + psi3) + p.a1
    cz1 = p.c2 * math.cos(t[1]) + k * math.cos(t[1] + t[2] + psi3)
    centre = _rz(t[0]) @ np.array([cx1, p.b, 0.0]) + np.array([0.0, 0.0, p.c1 + cz1])
    rot = _rz(t[0]) @ _ry(t[1] + t[2]) @ _rz(t[3]) @ _ry(t[4]) @ _rz(t[5])
    out = np.eye(4)
    out[:3, :3] = rot
    out[:3, 3] = centre + p.c4 * rot[:, 2]
    return out


def _unit(v: Array) -> Array:
    n = float(np.linalg.norm(v))
    if n < 1e-12:
        raise NotOpwError("a degenerate axis direction")
    return np.asarray(v / n, dtype=np.float64)


def _wrist_centre(axes: Array, points: Array) -> Array:
    """The point nearest (least squares) to three lines."""
    a, rhs = np.zeros((3, 3)), np.zeros(3)
    for w, p in zip(axes, points, strict=True):
        proj = np.eye(3) - np.outer(w, w)
        a += proj
        rhs += proj @ p
    return np.asarray(np.linalg.lstsq(a, rhs, rcond=None)[0], dtype=np.float64)


def _line_distance(w1: Array, p1: Array, w2: Array, p2: Array) -> float:
    """Distance (m) between the line through ``p1`` along the unit ``w1`` and the line through
    ``p2`` along the unit ``w2``."""
    d = p2 - p1
    normal = np.cross(w1, w2)
    size = float(np.linalg.norm(normal))
    if size < 1e-9:  # parallel: the spacing
        return float(np.linalg.norm(d - float(d @ w1) * w1))
    return abs(float(d @ normal)) / size


def _wrist_gap(names: tuple[str, ...], axes: Array, points: Array
               ) -> tuple[float, tuple[str, str]]:
    """The largest distance (m) between two wrist axes (joints 4 to 6) and their joints."""
    gaps = [(_line_distance(axes[i], points[i], axes[j], points[j]), (names[i], names[j]))
            for i, j in ((3, 4), (3, 5), (4, 5))]
    return max(gaps, key=lambda g: g[0])


def _axes_at_zero(chain: KinematicChain, tip: str) -> tuple[tuple[str, ...], Array, Array]:
    path = [j for j in chain.path_to(tip) if j.actuated]
    if chain.dof != 6 or len(path) != 6:
        raise NotOpwError(f"needs 6 actuated joints between the root and {tip}, has "
                          f"{len(path)} of {chain.dof}")
    if any(j.type is not JointType.REVOLUTE for j in path):
        raise NotOpwError("a joint is not revolute: " + ", ".join(
            j.name for j in path if j.type is not JointType.REVOLUTE))
    frames = {j.name: f for j, f in chain.joint_frames(np.zeros(chain.dof))}
    axes = np.array([_unit(frames[j.name][:3, :3] @ np.asarray(j.axis, float)) for j in path])
    points = np.array([frames[j.name][:3, 3] for j in path])
    return tuple(j.name for j in path), axes, points


def _parameters(chain: KinematicChain, tip: str, axes: Array, points: Array
                ) -> tuple[OpwParameters, Array]:
    """Parameters read at zero and the OPW base frame in the root frame."""
    w1, w2, w3, w4, w5, w6 = axes
    if abs(float(w1 @ w2)) > 0.1:
        raise NotOpwError(f"joint 2 is not perpendicular to joint 1 (cos {float(w1 @ w2):.3f})")
    z = w1
    y = _unit(w2 - float(w2 @ z) * z)
    x = np.cross(y, z)
    origin = points[0] - float(points[0] @ z) * z  # the foot of joint 1's axis
    centre = _wrist_centre(axes[3:], points[3:])
    if (points[1] - origin) @ x < 0 or (abs((points[1] - origin) @ x) < 1e-9
                                        and (centre - origin) @ x < 0):
        x, y = -x, -y

    def plane(v: Array) -> Array:
        return np.array([(v - origin) @ x, (v - origin) @ z])

    up = plane(points[2]) - plane(points[1])
    theta2 = math.atan2(up[0], up[1])
    fore = plane(centre) - plane(points[2])
    w4_plane = np.array([w4 @ x, w4 @ z])
    s4 = 1 if w4_plane @ fore >= 0 else -1
    forward = s4 * w4
    theta23 = math.atan2(float(forward @ x), float(forward @ z))
    psi3 = math.atan2(fore[0], fore[1]) - theta23
    k = float(np.linalg.norm(fore))
    base = np.eye(4)
    base[:3, :3] = np.column_stack([x, y, z])
    base[:3, 3] = origin
    r0c = base[:3, :3] @ _ry(theta23)
    v5 = r0c.T @ w5
    s5 = 1 if v5[1] >= 0 else -1
    theta4 = math.atan2(-s5 * v5[0], s5 * v5[1])
    tool = chain.frame_pose(tip, np.zeros(chain.dof))
    rce = r0c.T @ tool[:3, :3]
    theta6 = math.atan2(rce[1, 0], rce[0, 0]) - theta4
    thetas = (0.0, theta2, theta23 - theta2, theta4, 0.0, theta6)
    signs = (1, 1 if w2 @ y > 0 else -1, 1 if w3 @ y > 0 else -1, s4, s5,
             1 if w6 @ forward > 0 else -1)
    params = OpwParameters(
        a1=float((points[1] - origin) @ x), a2=k * math.sin(psi3), b=float((centre - origin) @ y),
        c1=float((points[1] - origin) @ z), c2=float(np.linalg.norm(up)), c3=k * math.cos(psi3),
        c4=float((tool[:3, 3] - centre) @ forward),
        offsets=tuple(_wrap(-t) + 0.0 for t in thetas),  # type: ignore[arg-type]
        sign_corrections=signs)  # type: ignore[arg-type]
    return params, base


def _rotation_angle(a: Array, b: Array) -> float:
    """The angle (rad) of the rotation between ``a`` and ``b``: ||a - b||_F = 2 sqrt(2)
    sin(angle / 2), accurate near 0 (where the trace formula's acos is not)."""
    chord = float(np.linalg.norm(a - b)) / math.sqrt(8.0)
    return 2.0 * math.asin(min(1.0, chord))


def fit_opw(chain: KinematicChain, tip: str = "tool0", samples: int = 1000,
            seed: int = 0) -> OpwFit:
    """OPW parameters of ``chain`` (tool frame ``tip``: a role or a link name) and their
    measured deviation from it at ``samples`` random configurations inside the limits.

    Raises:
        NotOpwError: when no parameters can be read (not six revolute joints, joint 2 not
            across joint 1).
    """
    link = chain.frames.get(tip, tip)
    names, axes, points = _axes_at_zero(chain, link)
    params, base = _parameters(chain, link, axes, points)
    gap, gap_joints = _wrist_gap(names, axes, points)
    rng = np.random.default_rng(seed)
    lo, hi = chain.lower(), chain.upper()
    inv_base = invert(base)
    worst_p = worst_r = 0.0
    for _ in range(samples):
        q = rng.uniform(lo, hi)
        want = inv_base @ chain.frame_pose(link, q)
        got = opw_forward(params, q)
        worst_p = max(worst_p, float(np.linalg.norm(want[:3, 3] - got[:3, 3])))
        worst_r = max(worst_r, _rotation_angle(want[:3, :3], got[:3, :3]))
    return OpwFit(params, base, link, names, gap, gap_joints, worst_p, worst_r, samples)
