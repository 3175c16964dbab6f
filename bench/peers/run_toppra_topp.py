"""Time parameterization with toppra 0.6.10: python run_toppra_topp.py PROBLEMS.json RESULTS.json

As in toppra's quickstart: path = SplineInterpolator(linspace(0, 1, n), waypoints) (cubic,
not-a-knot), constraints JointVelocityConstraint(vmax) and JointAccelerationConstraint(amax)
(symmetric), TOPPRA([vel, acc], path, parametrizer="ParametrizeConstAccel") with default
gridpoints and solver; compute_trajectory() with zero start/end path velocity. Timed: building
the spline, the constraints and the instance, compute_trajectory() and the 100 Hz sampling
(roboplan's timed call samples at 100 Hz, so every solver's time includes it; "timing_seconds":
without the sampling).
"""

import numpy as np
import peerio
import toppra as ta
import toppra.algorithm as algo
import toppra.constraint as constraint

spec, out = peerio.args()
vmax, amax = np.array(spec["vmax"], float), np.array(spec["amax"], float)
ta.setup_logging("WARNING")


def parameterize(waypoints):
    path = ta.SplineInterpolator(np.linspace(0, 1, len(waypoints)), waypoints)
    vel = constraint.JointVelocityConstraint(np.stack([-vmax, vmax], axis=1))
    acc = constraint.JointAccelerationConstraint(np.stack([-amax, amax], axis=1))
    return algo.TOPPRA([vel, acc], path, parametrizer="ParametrizeConstAccel").compute_trajectory()


def solve(p):
    wp = peerio.waypoints(p, len(vmax))
    traj, sec = peerio.timed(parameterize, wp)
    if traj is None:
        return {"success": False, "seconds": sec, "duration_s": None, "samples": None}
    (t, q), sampling = peerio.timed(sample, traj)
    return {
        "success": True,
        "seconds": sec + sampling,
        "timing_seconds": sec,
        "duration_s": float(traj.duration),
        "samples": {"t": t, "q": q},
    }


def sample(traj):
    """The trajectory's 100 Hz samples (t, q)."""
    t = peerio.sample_times(float(traj.duration))
    return t, np.asarray(traj(t))


peerio.write(
    out,
    peer="toppra",
    dist="toppra",
    stage="topp",
    results=peerio.solve_all(spec["problems"], solve),
    notes="cubic spline through the waypoints (it may overshoot between them); seconds = "
    "the parameterisation + its 100 Hz samples, timing_seconds = without the samples",
)
