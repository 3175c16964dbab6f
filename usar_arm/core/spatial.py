"""Rotations and rigid transforms (numpy only).

Conventions: right-handed frames; angles in radians; lengths in metres. Roll-pitch-yaw is the
fixed-axis convention of URDF and of USARSim's `Orientation r,p,y`:
``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``. Transforms are 4x4 homogeneous matrices.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
# A vector argument: a sequence of floats or any float numpy array (metres or radians).
Vector = Sequence[float] | NDArray[np.floating]


def rot_x(angle: float) -> Array:
    """Rotation by ``angle`` (rad) about x."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> Array:
    """Rotation by ``angle`` (rad) about y."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle: float) -> Array:
    """Rotation by ``angle`` (rad) about z."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rpy_to_matrix(rpy: Vector) -> Array:
    """Rotation matrix of fixed-axis roll, pitch, yaw (rad): Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = (float(v) for v in rpy)
    return rot_z(y) @ rot_y(p) @ rot_x(r)


def matrix_to_rpy(rot: Array) -> tuple[float, float, float]:
    """Roll, pitch, yaw (rad) of a rotation matrix, pitch in [-pi/2, pi/2].

    At gimbal lock (|pitch| = pi/2) roll is set to 0 and yaw carries the rotation.
    """
    r = np.asarray(rot, dtype=float)
    sy = -r[2, 0]
    sy = min(1.0, max(-1.0, sy))
    pitch = float(np.arcsin(sy))
    if abs(abs(sy) - 1.0) < 1e-12:
        roll = 0.0
        yaw = float(np.arctan2(-r[0, 1], r[1, 1]))
    else:
        roll = float(np.arctan2(r[2, 1], r[2, 2]))
        yaw = float(np.arctan2(r[1, 0], r[0, 0]))
    return roll, pitch, yaw


def transform(rot: Array | None = None, pos: Vector | None = None) -> Array:
    """A 4x4 homogeneous transform from a rotation matrix and a position (m)."""
    t = np.eye(4)
    if rot is not None:
        t[:3, :3] = rot
    if pos is not None:
        t[:3, 3] = np.asarray(pos, dtype=float)
    return t


def transform_from_xyz_rpy(xyz: Vector, rpy: Vector) -> Array:
    """A 4x4 transform from a position (m) and fixed-axis roll, pitch, yaw (rad)."""
    return transform(rpy_to_matrix(rpy), xyz)


def invert(t: Array) -> Array:
    """Inverse of a rigid 4x4 transform."""
    out = np.eye(4)
    rt = t[:3, :3].T
    out[:3, :3] = rt
    out[:3, 3] = -rt @ t[:3, 3]
    return out


def rotation_angle(rot: Array) -> float:
    """Angle (rad, in [0, pi]) of a rotation matrix."""
    c = (np.trace(rot) - 1.0) / 2.0
    return float(np.arccos(min(1.0, max(-1.0, c))))


def rotation_distance(a: Array, b: Array) -> float:
    """Angle (rad) of the rotation that takes ``a`` to ``b``."""
    return rotation_angle(a.T @ b)


def angle_between(u: Vector, v: Vector) -> float:
    """Angle (rad) between two non-zero vectors."""
    a = np.asarray(u, dtype=float)
    b = np.asarray(v, dtype=float)
    c = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
    # atan2 form is accurate for tiny angles where arccos is not.
    s = float(np.linalg.norm(np.cross(a, b)) / (np.linalg.norm(a) * np.linalg.norm(b)))
    return float(np.arctan2(s, c))


def rotation_onto(axis: Vector, direction: Vector, half_turn_about: Vector) -> Array:
    """The smallest rotation (3x3) taking the unit vector ``axis`` onto ``direction`` (any
    length): the identity within 1.4 urad of ``axis`` (1 - cos below 1e-12), and where
    ``direction`` is as near opposite, the half turn about the unit vector ``half_turn_about``
    (normal to ``axis``)."""
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    a = np.asarray(axis, dtype=float)
    c = float(a @ d)
    if c > 1 - 1e-12:
        return np.eye(3)
    if c < -1 + 1e-12:
        n = np.asarray(half_turn_about, dtype=float)
        return 2.0 * np.outer(n, n) - np.eye(3)
    v = np.cross(a, d)
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + vx + vx @ vx / (1 + c)


def log_so3(rot: Array) -> Array:
    """Rotation vector (axis * angle, rad) of a rotation matrix."""
    angle = rotation_angle(rot)
    if angle < 1e-9:
        return np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]]) / 2.0
    if np.pi - angle < 1e-6:
        # Near pi: axis from the diagonal.
        d = np.sqrt(np.maximum((np.diag(rot) + 1.0) / 2.0, 0.0))
        k = int(np.argmax(d))
        axis = np.zeros(3)
        axis[k] = d[k]
        for j in range(3):
            if j != k:
                axis[j] = (rot[k, j] + rot[j, k]) / (4.0 * d[k])
        return axis / np.linalg.norm(axis) * angle
    w = np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]])
    return w * (angle / (2.0 * np.sin(angle)))


def pose_error(target: Array, measured: Array) -> tuple[Array, float, float]:
    """The pose error (the one of the project): the 6-vector (position m; rotation rad, world
    axes) from ``measured`` to ``target`` (4x4 each), and its two norms (m, rad)."""
    e = np.empty(6)
    e[:3] = target[:3, 3] - measured[:3, 3]
    e[3:] = log_so3(target[:3, :3] @ measured[:3, :3].T)
    return e, float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:]))


def exp_so3(w: Vector) -> Array:
    """Rotation matrix of a rotation vector (axis * angle, rad)."""
    v = np.asarray(w, dtype=float)
    angle = float(np.linalg.norm(v))
    if angle < 1e-12:
        return np.eye(3)
    k = v / angle
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * kx + (1.0 - np.cos(angle)) * (kx @ kx)


def quat_from_matrix(rot: Array) -> Array:
    """Unit quaternion (w, x, y, z) of a rotation matrix, with w >= 0."""
    r = np.asarray(rot, dtype=float)
    tr = np.trace(r)
    if tr > 0:
        s = np.sqrt(tr + 1.0) * 2
        q = np.array([0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s,
                      (r[1, 0] - r[0, 1]) / s])
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2]) * 2
        q = np.array([(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s,
                      (r[0, 2] + r[2, 0]) / s])
    elif r[1, 1] > r[2, 2]:
        s = np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2]) * 2
        q = np.array([(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s,
                      (r[1, 2] + r[2, 1]) / s])
    else:
        s = np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1]) * 2
        q = np.array([(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s,
                      (r[1, 2] + r[2, 1]) / s, 0.25 * s])
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def matrix_from_quat(q: Vector) -> Array:
    """Rotation matrix of a quaternion (w, x, y, z); normalised first."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


# The USARSim wire frame is x forward, y right, z down; REP-103 is x forward, y left, z up.
# The two differ by a rotation of pi about x: (x, y, z) -> (x, -y, -z).
FLIP_X = np.diag([1.0, -1.0, -1.0])


def zdown_to_zup_point(p: Vector) -> Array:
    """A position (m) in the USARSim z-down frame expressed in the REP-103 z-up frame."""
    return FLIP_X @ np.asarray(p, dtype=float)


def zdown_to_zup_rotation(rot: Array) -> Array:
    """A rotation expressed in z-down frames, re-expressed between the matching z-up frames."""
    return FLIP_X @ np.asarray(rot, dtype=float) @ FLIP_X


def zdown_to_zup_transform(t: Array) -> Array:
    """A transform between z-down frames, re-expressed between the matching z-up frames."""
    f = transform(FLIP_X)
    return f @ t @ f
