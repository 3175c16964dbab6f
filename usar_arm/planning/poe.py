"""Vectorised forward kinematics and Jacobians of a serial chain (product of exponentials).

Built from the chain's joint axes and points at the zero configuration and the links' zero poses,
which represents the URDF exactly: a link moved by the first m joints sits at
exp(xi_1 q_1) ... exp(xi_m q_m) T_link(0). Every function works on a batch of N configurations at
once, so the per-configuration Python overhead vanishes for large N; :mod:`.kinematics`
(Pinocchio) is the reference these are tested against.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array


def _rodrigues(w: Array, angle: Array) -> Array:
    """Rotation matrices (N, 3, 3) about one unit axis ``w`` by N angles."""
    k = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    return _rodrigues_k(k, np.outer(w, w), np.asarray(angle, float))


def _rodrigues_k(k: Array, ww: Array, angle: Array) -> Array:
    """Rodrigues with the axis' cross matrix ``k`` and outer product ``ww`` precomputed:
    R = ww + cos(a) (I - ww) + sin(a) k."""
    c = np.cos(angle)[:, None, None]
    s = np.sin(angle)[:, None, None]
    return ww + c * (np.eye(3) - ww) + s * k


class PoeModel:
    """A serial chain as twists at the zero configuration.

    Args:
        chain: the robot description (its actuated joints must form one path from the root).
    """

    def __init__(self, chain: KinematicChain):
        self.chain = chain
        zero = np.zeros(chain.dof)
        actuated = [(j, f) for j, f in chain.joint_frames(zero) if j.actuated]
        self.axes = np.array([f[:3, :3] @ np.asarray(j.axis, float) for j, f in actuated])
        self.points = np.array([f[:3, 3] for _, f in actuated])
        self.revolute = np.array([j.type.value == "revolute" for j, _ in actuated])
        self._names = [j.name for j, _ in actuated]
        self._zero_poses = chain.link_poses(zero)
        self._moving: dict[str, int] = {}
        self._k = [np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
                   for w in self.axes]
        self._ww = [np.outer(w, w) for w in self.axes]

    @property
    def dof(self) -> int:
        """Number of joints."""
        return len(self.axes)

    def joints_moving(self, link: str) -> int:
        """How many of the chain's joints (from the first) move ``link``.

        Raises:
            ValueError: the link is moved by joints that are not a prefix of the chain.
        """
        if link not in self._moving:
            path = [j.name for j in self.chain.path_to(link) if j.actuated]
            if path != self._names[: len(path)]:
                raise ValueError(f"link {link} is moved by {path}: not a prefix of the serial "
                                 f"chain {self._names}")
            self._moving[link] = len(path)
        return self._moving[link]

    def accumulate(self, q: Array) -> tuple[Array, Array, Array, Array]:
        """Products of the first m exponentials for m = 0..n: rotations (N, n+1, 3, 3) and
        positions (N, n+1, 3), plus each joint's current axis (N, n, 3) and point (N, n, 3)."""
        q = np.atleast_2d(np.asarray(q, float))
        n_cfg, n = len(q), self.dof
        rots = np.empty((n_cfg, n + 1, 3, 3))
        poss = np.empty((n_cfg, n + 1, 3))
        axes = np.empty((n_cfg, n, 3))
        points = np.empty((n_cfg, n, 3))
        rot = np.broadcast_to(np.eye(3), (n_cfg, 3, 3))
        pos = np.zeros((n_cfg, 3))
        rots[:, 0], poss[:, 0] = rot, pos
        for i in range(n):
            w, p = self.axes[i], self.points[i]
            axes[:, i] = rot @ w
            rp = rot @ p
            points[:, i] = rp + pos
            if self.revolute[i]:
                e = _rodrigues_k(self._k[i], self._ww[i], q[:, i])
                rot = rot @ e
                pos = pos + rp - rot @ p  # T_prev * exp: p_new = pos + R (I - E) p
            else:
                pos = pos + axes[:, i] * q[:, i:i + 1]
            rots[:, i + 1], poss[:, i + 1] = rot, pos
        return rots, poss, axes, points

    def link_poses(self, q: Array, links: Sequence[str]) -> Array:
        """Poses (N, len(links), 4, 4) of the given links at configurations q (N, n)."""
        rots, poss, _, _ = self.accumulate(q)
        n_cfg = len(rots)
        out = np.zeros((n_cfg, len(links), 4, 4))
        out[..., 3, 3] = 1.0
        for k, link in enumerate(links):
            m = self.joints_moving(link)
            zero = self._zero_poses[link]
            out[:, k, :3, :3] = rots[:, m] @ zero[:3, :3]
            out[:, k, :3, 3] = rots[:, m] @ zero[:3, 3] + poss[:, m]
        return out

    def frame_jacobian(self, q: Array, frame: str) -> tuple[Array, Array]:
        """Poses (N, 4, 4) and LOCAL_WORLD_ALIGNED Jacobians (N, 6, n) of ``frame``."""
        name = self.chain.frames.get(frame, frame)
        if self.joints_moving(name) != self.dof:
            raise ValueError(f"frame {name} is not moved by every joint")
        rots, poss, axes, points = self.accumulate(q)
        zero = self._zero_poses[name]
        n_cfg = len(rots)
        poses = np.zeros((n_cfg, 4, 4))
        poses[:, :3, :3] = rots[:, -1] @ zero[:3, :3]
        poses[:, :3, 3] = rots[:, -1] @ zero[:3, 3] + poss[:, -1]
        poses[:, 3, 3] = 1.0
        jac = np.zeros((n_cfg, 6, self.dof))
        lever = poses[:, None, :3, 3] - points
        rev = self.revolute
        jac[:, :3, rev] = np.cross(axes[:, rev], lever[:, rev]).transpose(0, 2, 1)
        jac[:, 3:, rev] = axes[:, rev].transpose(0, 2, 1)
        jac[:, :3, ~rev] = axes[:, ~rev].transpose(0, 2, 1)
        return poses, jac

