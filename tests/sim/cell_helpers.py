"""Helpers of the physical cell's tests: where the KR60's tool changer is by the robot data
alone (forward kinematics of the spec, the ground truth), a small numeric IK to put it
somewhere, and driving the arm there over the wire."""

from __future__ import annotations

import numpy as np

from usar_arm.core.spatial import Array, invert
from usar_arm.sim.robot_spec import RobotSpec, builtin_robots, part_poses
from usar_arm.usarsim.client import UsarClient

KR60 = builtin_robots()["USARBot.KR60"]
ARM = KR60.actuators[0]


def changer_pose(q: np.ndarray, spec: RobotSpec = KR60) -> Array:
    """The KR60's tool changer pose (4x4, z-down, robot at the origin) at joint values ``q``."""
    changer = spec.tool_changers[0]
    act = spec.actuators[0]
    zero = {jt.child: jt.frame() for jt in act.joints}
    out: Array = part_poses(act, list(q))[changer.parent] @ invert(zero[changer.parent]) \
        @ changer.frame()
    return out


STARTS = (np.array([0.0, -0.4, 0.6, 0.0, -1.2, 0.0]), np.array([0.0, -0.4, 0.6, 0.0, 1.2, 0.0]),
          np.array([0.0, 0.0, 0.0, 0.0, -1.5, 0.0]), np.array([0.0, -0.8, 1.0, 0.0, 1.5, 0.0]))
"""Where :func:`ik_down` starts (the first solution within the joint limits is taken)."""


X_AXIS = np.array([-0.6, 0.8, 0.0])
"""The tool changer's x axis :func:`ik_down` asks for (z-down world): the one the KR60 has
over the table with its wrist unturned, so that every pose it gives is one wrist apart."""


def ik_down(target: np.ndarray, near: np.ndarray | None = None) -> np.ndarray:
    """Joint values within the limits putting the tool changer at ``target`` (m, z-down) with
    its approach axis (+z) pointing straight down (+z of the world) and its x axis along
    :data:`X_AXIS` (turned about the vertical toward the target); tried from ``near`` first."""
    heading = np.arctan2(target[1], target[0])
    c, s = np.cos(heading), np.sin(heading)
    x_axis = np.array([c * X_AXIS[0] - s * X_AXIS[1], s * X_AXIS[0] + c * X_AXIS[1], 0.0])
    starts = ((near,) if near is not None else ()) + STARTS
    found = [q for q in (_solve(target, x_axis, start) for start in starts) if q is not None]
    assert found, f"no IK solution within the limits for {target}"
    return found[0]


def _solve(target: np.ndarray, x_axis: np.ndarray, start: np.ndarray) -> np.ndarray | None:
    """Damped least squares on the spec's kinematics from ``start``; None when it does not
    converge or ends outside the joint limits.

    The spherical wrist reaches nearly the same pose turned over, (a4 + pi, -a5, a6 + pi):
    where the solution found needs a4 at +-pi, just past the +-3.14 limits (rounding decides
    which side on a given CPU), the descent is run again from that twin, which has a4 near 0
    (the KR60's wrist axes are a few mm apart, so the twin itself is not a solution)."""

    def err(x: np.ndarray) -> np.ndarray:
        pose = changer_pose(x)
        return np.concatenate([pose[:3, 3] - target, pose[:3, 2] - (0.0, 0.0, 1.0),
                               pose[:3, 0] - x_axis])

    def descend(q: np.ndarray) -> np.ndarray:
        for _ in range(200):
            e = err(q)
            if np.linalg.norm(e) < 1e-7:
                break
            jac = np.column_stack([(err(q + dq) - e) / 1e-6 for dq in np.eye(len(q)) * 1e-6])
            q = q - np.linalg.solve(jac.T @ jac + 1e-6 * np.eye(len(q)), jac.T @ e)
            q = (q + np.pi) % (2 * np.pi) - np.pi
        return q

    limits = [(jt.limit_low, jt.limit_high) for jt in ARM.joints]

    def good(q: np.ndarray) -> bool:
        inside = all(lo <= v <= hi for v, (lo, hi) in zip(q, limits, strict=True))
        return inside and bool(np.linalg.norm(err(q)) < 1e-5)

    q = descend(start.copy())
    if good(q):
        return q
    twin = q + np.array([0.0, 0.0, 0.0, np.pi, 0.0, np.pi])
    twin[4] = -q[4]
    q = descend((twin + np.pi) % (2 * np.pi) - np.pi)
    return q if good(q) else None


def drive(client: UsarClient, q: np.ndarray, tol: float = 6e-3, timeout: float = 20.0
          ) -> None:
    """ACT the KR60 to ``q`` and wait until ASTA is within ``tol`` rad of it."""
    client.act("KR60Arm", [float(v) for v in q])
    after = None
    import time

    deadline = time.monotonic() + timeout
    while True:
        asta = client.wait_asta("KR60Arm", after_time=after, timeout=5.0)
        if np.max(np.abs(np.array(asta.positions()) - q)) < tol:
            return
        assert time.monotonic() < deadline, (asta.positions(), q)
        after = asta.time
