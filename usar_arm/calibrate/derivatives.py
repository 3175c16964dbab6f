"""Analytic derivatives of the error model: how the measured frame's pose, and so each number
the fit compares, moves with each parameter and each joint value.

Every parameter changes one frame on the path from M to the measured frame: the base
(M_from_base_link = base_guess [exp(w) | v]), an actuated joint's origin or the tool joint's
origin ([R exp(w) | t + v]). With A the pose in M of the frame the correction is applied in
(base_guess for the base, the parent link for an origin) and R its nominal rotation:

* d position / d v_k = R_A e_k, no rotation;
* d / d w_k: a rotation about the axis a = R_A R exp(w) J_r(w) e_k (in M) through the corrected
  frame's origin o: d position = a x (p - o), d rotation = a.

A revolute joint turns everything after it about its axis in M through its origin; a prismatic
joint shifts it along its axis. The numbers' derivatives follow from those of the pose:
positions directly, printed roll/pitch/yaw by the inverse of their rate map, unquantised
orientations (rotation vector of R R_measured^T) by the inverse left Jacobian of SO(3). They
agree with central differences of :meth:`ErrorModel.poses` to ~1e-8 (tests/calibrate).
"""

from __future__ import annotations

import numpy as np

from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.parameters import ErrorModel, corrected, correction
from usar_arm.core.model import JointType
from usar_arm.core.spatial import Array


def _skew(v: Array) -> Array:
    """(3, 3) skew matrix of (3,)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def right_jacobian(w: Array) -> Array:
    """J_r(w) of SO(3): exp(w + dw) = exp(w) exp(J_r(w) dw) to first order."""
    theta = float(np.linalg.norm(w))
    k = _skew(w)
    if theta < 1e-8:
        return np.eye(3) - 0.5 * k
    return (np.eye(3) - (1 - np.cos(theta)) / theta ** 2 * k
            + (theta - np.sin(theta)) / theta ** 3 * (k @ k))


def _frames(model: ErrorModel, p: Array, q: Array, base: Array
            ) -> tuple[Array, list[tuple[int, Array, Array]], list[tuple[Array, Array, bool]]]:
    """The measured frame's poses (N, 4, 4); per corrected frame (parameter offset, A (N, 4, 4),
    its local axes' rotation R exp(w) J_r(w) (3, 3)); per actuated joint in q's order (its
    axis in M (N, 3), a point on it (N, 3), prismatic)."""
    joints, tool, b = model.split(p)
    n = len(q)
    col = {name: i for i, name in enumerate(model.joint_names)}
    corrections: list[tuple[int, Array, Array]] = []
    axes: list[tuple[Array, Array, bool]] = [(np.zeros((n, 3)), np.zeros((n, 3)), False)] \
        * len(model.joint_names)
    names = model.names
    t = np.tile(np.asarray(base, float), (n, 1, 1))
    if b is not None:
        corrections.append((names.index("base.x"), t.copy(),
                            correction(b)[:3, :3] @ right_jacobian(b[3:])))
        t = t @ correction(b)
    for j in model.path:
        d = joints.get(j.name) if j.actuated else (tool if j.name == model.tool_joint else None)
        nominal = j.origin.matrix()
        origin = nominal if d is None else corrected(nominal, d)
        if d is not None:
            first = names.index(f"{j.name}.origin.x" if j.actuated else "tool.x")
            corrections.append((first, t.copy(), origin[:3, :3] @ right_jacobian(d[3:])))
        t = t @ origin
        if j.actuated:
            axis = np.asarray(j.axis, float)
            axes[col[j.name]] = (t[:, :3, :3] @ axis, t[:, :3, 3].copy(),
                                 j.type is JointType.PRISMATIC)
            t = t @ _motion(j.type is JointType.PRISMATIC, axis, q[:, col[j.name]])
    return t, corrections, axes


def _motion(prismatic: bool, axis: Array, q: Array) -> Array:
    out = np.tile(np.eye(4), (len(q), 1, 1))
    if prismatic:
        out[:, :3, 3] = q[:, None] * axis
        return out
    k = _skew(axis)
    s, c = np.sin(q)[:, None, None], np.cos(q)[:, None, None]
    out[:, :3, :3] = np.eye(3) + s * k + (1 - c) * (k @ k)
    return out


def pose_jacobian(model: ErrorModel, p: Array, q: Array, base: Array
                  ) -> tuple[Array, Array]:
    """The measured frame's poses (N, 4, 4) and d(position m, rotation rad in M) / d p
    (N, 6, P), the rotation being the left increment: R(p + dp) = exp(J_rot dp) R(p)."""
    q = np.atleast_2d(np.asarray(q, float))
    poses, corrections, _ = _frames(model, p, q, base)
    out = np.zeros((len(q), 6, model.size))
    end = poses[:, :3, 3]
    for first, a, local in corrections:
        rot = a[:, :3, :3]
        out[:, :3, first:first + 3] = rot
        axes = rot @ local                            # (N, 3, 3): columns are the axes in M
        origin = a[:, :3, 3] + rot @ _origin_shift(model, p, first)
        lever = end - origin
        out[:, :3, first + 3:first + 6] = np.cross(axes, lever[:, :, None], axis=1)
        out[:, 3:, first + 3:first + 6] = axes
    return poses, out


def _origin_shift(model: ErrorModel, p: Array, first: int) -> Array:
    """Where the corrected frame's origin sits in A's axes (the nominal origin's translation
    plus the correction's v; for the base, v alone)."""
    name = model.names[first]
    v = p[first:first + 3]
    if name.startswith("base."):
        return v
    joint = name.split(".origin.")[0] if ".origin." in name else model.tool_joint
    nominal = next(j for j in model.path if j.name == joint).origin.matrix()
    return nominal[:3, 3] + v


def joint_pose_jacobian(model: ErrorModel, p: Array, q: Array, base: Array
                        ) -> tuple[Array, Array]:
    """The poses (N, 4, 4) and d(position, rotation) / d q (N, 6, n) in M."""
    q = np.atleast_2d(np.asarray(q, float))
    poses, _, axes = _frames(model, p, q, base)
    out = np.zeros((len(q), 6, q.shape[1]))
    end = poses[:, :3, 3]
    for j, (axis, point, prismatic) in enumerate(axes):
        if prismatic:
            out[:, :3, j] = axis
        else:
            out[:, :3, j] = np.cross(axis, end - point)
            out[:, 3:, j] = axis
    return poses, out


def number_jacobian(poses: Array, pose_jac: Array, t: qm.Targets) -> Array:
    """d errors / d x (N, 6, K) from the poses' derivatives ``pose_jac`` (N, 6, K): positions
    as they are; printed roll, pitch, yaw by the inverse rate map; rotation vectors of
    R R_measured^T by the inverse left Jacobian; unused numbers zero."""
    out = pose_jac.copy()
    rot = poses[:, :3, :3]
    rpy = qm.rpy_many(rot)
    cp, sp = np.cos(rpy[:, 1]), np.sin(rpy[:, 1])
    cy, sy = np.cos(rpy[:, 2]), np.sin(rpy[:, 2])
    cp = np.where(np.abs(cp) < 1e-9, 1e-9, cp)
    w = pose_jac[:, 3:, :]
    planar = cy[:, None] * w[:, 0] + sy[:, None] * w[:, 1]
    printed = np.stack([planar / cp[:, None], -sy[:, None] * w[:, 0] + cy[:, None] * w[:, 1],
                        (sp / cp)[:, None] * planar + w[:, 2]], axis=1)
    e = qm.log_many(rot @ np.transpose(t.rotations, (0, 2, 1)))
    vector = np.einsum("nij,njk->nik", _left_jacobian_inverse(e), w)
    out[:, 3:, :] = np.where(t.quantised_rot[:, None, None], printed, vector)
    return out * t.used[:, :, None]


def _left_jacobian_inverse(e: Array) -> Array:
    """(N, 3, 3) J_l^{-1} of SO(3) at rotation vectors e (N, 3)."""
    theta = np.linalg.norm(e, axis=1)
    k = np.zeros((len(e), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -e[:, 2], e[:, 1], -e[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = e[:, 2], -e[:, 1], e[:, 0]
    safe = np.where(theta < 1e-6, 1.0, theta)
    coef = np.where(theta < 1e-6, 1.0 / 12.0,
                    (1.0 / safe ** 2) - (1 + np.cos(safe)) / (2 * safe * np.sin(safe)))
    return np.eye(3) - 0.5 * k + coef[:, None, None] * (k @ k)
