"""IK with TRAC-IK (pytracik 0.0.3): python run_pytracik_ik.py PROBLEMS.json RESULTS.json

Solver: trac_ik.TracIK(base, tip, urdf, timeout=timeout_s, epsilon=min(tolerances),
solver_type="Speed" (the default)). Timed: the raw binding call
pytracik.ik(solver, seed, x, y, z, qx, qy, qz, qw) alone (TracIK.ik() would first convert a
rotation matrix back to a quaternion with an eigen-decomposition; the problem already gives
the quaternion).
"""

import numpy as np
import peerio
import pytracik
from trac_ik import TracIK

spec, out = peerio.args()
tol = spec["tolerance"]
eps = min(tol["position_m"], tol["orientation_rad"]) / 3**0.5
solver = TracIK(
    spec["base_link"], spec["tip_link"], spec["urdf"], timeout=spec["timeout_s"], epsilon=eps
)
chain = [
    name
    for name, kind, _ in peerio.chain_path(spec["urdf"], spec["base_link"], spec["tip_link"])
    if kind != "fixed"
]
if solver.dof != len(chain):
    raise SystemExit(f"TRAC-IK chain has {solver.dof} joints, URDF chain {chain}")
names = spec["joint_names"]


def solve(p):
    seed = np.array(peerio.reorder(p["seed"], names, chain), float)
    x, y, z = p["xyz"]
    w, qx, qy, qz = p["quat_wxyz"]
    r, sec = peerio.timed(pytracik.ik, solver._ik_solver, seed, x, y, z, qx, qy, qz, w)
    ok = bool(r[0] >= 0)
    return {"success": ok, "seconds": sec, "q": peerio.reorder(r[1:], chain, names) if ok else None}


peerio.write(
    out,
    peer="pytracik",
    dist="pytracik",
    stage="ik",
    results=peerio.solve_all(spec["problems"], solve),
    settings={"solver_type": "Speed", "timeout_s": spec["timeout_s"], "epsilon": eps},
)
