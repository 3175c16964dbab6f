"""Joining timed pieces into one timeline: the moves of a cycle as one trajectory, and their
ASTA feedback as one series (for a bag or a plot of the whole cycle).

Between the pieces (planning, settling, tip correction) the arm holds: the joined trajectory
holds the last position at rest there.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import pairwise

import numpy as np

from usar_arm.control.trajectory import ExecutedSamples, MotionLimits, Trajectory
from usar_arm.core.errors import InvalidInputError


def join_trajectories(pieces: Sequence[tuple[float, Trajectory]], rate: float = 250.0
                      ) -> Trajectory:
    """One trajectory sampled at ``rate`` (Hz) through ``(start s, trajectory)`` pieces.

    Pieces must share joint names and must not overlap in time; the first starts the
    timeline (its start is time 0). Samples are linearly interpolated (at 250 Hz or more
    from 500 Hz plans this is within 1e-6 rad).
    """
    if not pieces:
        raise InvalidInputError("nothing to join: no trajectories")
    pieces = sorted(pieces, key=lambda p: p[0])
    names = pieces[0][1].joint_names
    origin = pieces[0][0]
    for (s0, a), (s1, b) in pairwise(pieces):
        if b.joint_names != names:
            raise InvalidInputError(f"cannot join trajectories of joints {b.joint_names} and "
                                    f"{names}")
        if s1 < s0 + a.duration - 1e-6:
            raise InvalidInputError(f"the trajectory starting at {s1 - origin:.3f} s overlaps "
                                    f"the one before (ends at {s0 + a.duration - origin:.3f} s)")
    end = pieces[-1][0] + pieces[-1][1].duration - origin
    t = np.arange(0.0, end + 0.5 / rate, 1.0 / rate)
    n = len(names)
    q, qd, qdd = (np.empty((len(t), n)) for _ in range(3))
    for k, (start, traj) in enumerate(pieces):
        begin = start - origin
        stop = pieces[k + 1][0] - origin if k + 1 < len(pieces) else np.inf
        inside = (t >= begin) & (t < stop)
        local = np.clip(t[inside] - begin, 0.0, traj.duration)
        for j in range(n):
            q[inside, j] = np.interp(local, traj.t, traj.q[:, j])
            qd[inside, j] = np.interp(local, traj.t, traj.qd[:, j])
            qdd[inside, j] = np.interp(local, traj.t, traj.qdd[:, j])
        holding = inside & (t - begin > traj.duration)
        qd[holding] = 0.0
        qdd[holding] = 0.0
    waypoints = np.vstack([p[1].waypoints for p in pieces])
    limits = pieces[0][1].limits
    widest = MotionLimits(limits.lower, limits.upper,
                          *(np.max([getattr(p[1].limits, k) for p in pieces], axis=0)
                            for k in ("velocity", "acceleration", "jerk")))
    motions = {p[1].motion for p in pieces}
    return Trajectory(names, t, q, qd, qdd, waypoints, widest,
                      motions.pop() if len(motions) == 1 else "cycle", "joined",
                      {"pieces": len(pieces), "starts_s": [p[0] - origin for p in pieces]})


def join_executed(pieces: Sequence[tuple[float, ExecutedSamples]], origin: float
                  ) -> ExecutedSamples:
    """One series of samples from ``(start s, samples)`` pieces, times relative to
    ``origin`` (s on the same clock as the starts); samples before ``origin`` and duplicates
    (same time) are dropped."""
    ts = [start - origin + s.t for start, s in pieces if len(s.t)]
    qs = [s.q for _, s in pieces if len(s.t)]
    if not ts:
        raise InvalidInputError("nothing to join: no executed samples")
    t, q = np.concatenate(ts), np.vstack(qs)
    order = np.argsort(t, kind="stable")
    t, q = t[order], q[order]
    keep = np.concatenate([[True], np.diff(t) > 1e-9]) & (t >= 0)
    return ExecutedSamples(t[keep], q[keep])
