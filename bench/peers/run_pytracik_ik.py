"""IK with TRAC-IK (pytracik 0.0.3): python run_pytracik_ik.py PROBLEMS.json RESULTS.json

Solver: trac_ik.TracIK(base, tip, urdf, timeout=timeout_s, epsilon=min(tolerances),
solver_type="Speed" (the default)). Timed: the raw binding call
pytracik.ik(solver, seed, x, y, z, qx, qy, qz, qw) alone (TracIK.ik() would first convert a
rotation matrix back to a quaternion with an eigen-decomposition; the problem already gives
the quaternion).
"""

import xml.etree.ElementTree as ET

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
# pytracik 0.0.3 reads a joint with a <safety_controller> (example-robot-data's Panda) as
# limited to [0, 0] (or [0, upper]), so every pose failed: such limits are set back to the
# URDF's <limit> values; solvers that read the limits right are left as they are.
_limit = {
    j.get("name"): j.find("limit")
    for j in ET.parse(spec["urdf"]).getroot().findall("joint")
    if j.find("limit") is not None
}
urdf_limits = np.array(
    [[float(_limit[n].get("lower")) for n in chain], [float(_limit[n].get("upper")) for n in chain]]
)
limits_reset = bool(np.abs(np.array(solver.joint_limits) - urdf_limits).max() > 1e-4)
if limits_reset:
    solver.joint_limits = (list(urdf_limits[0]), list(urdf_limits[1]))


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
    settings={"solver_type": "Speed", "timeout_s": spec["timeout_s"], "epsilon": eps,
              "joint_limits_reset_from_urdf": limits_reset},
)
