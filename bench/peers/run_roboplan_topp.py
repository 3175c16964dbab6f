"""Time parameterization with roboplan 0.7.0 (its TOPP-RA wrapper over the toppra C++ library):
python run_roboplan_topp.py PROBLEMS.json RESULTS.json

roboplan parameterizes a JointPath of a Scene, and the TOPP problem file has no robot, so this
runner builds a bare chain URDF with the problem's joint names (revolute, no geometry; position
limits from "lower"/"upper" when given, else +-1000 rad), loads vmax/amax with
importJointLimitsFromConfig. Timed: PathParameterizerTOPPRA(scene, group).generate(JointPath,
TOPPRAOptions(dt=0.01)) - which already samples at 100 Hz, so the sampling is in the time.
Default mode Hermite: a cubic Hermite spline with ZERO VELOCITY AT EVERY WAYPOINT (exact path,
slower than toppra's spline through the waypoints, which does not stop).
"""

import tempfile
from pathlib import Path

import numpy as np
import peerio
from roboplan import core
from roboplan.toppra import PathParameterizerTOPPRA, TOPPRAOptions

spec, out = peerio.args()
names = spec["joint_names"]
lo = spec.get("lower") or [-1000.0] * len(names)
hi = spec.get("upper") or [1000.0] * len(names)
links = "".join(f'<link name="l{i + 1}"/>' for i in range(len(names)))
joints = "".join(
    f'<joint name="{n}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
    f'<axis xyz="0 0 1"/><limit lower="{lo[i]!r}" upper="{hi[i]!r}" effort="1" '
    f'velocity="{float(spec["vmax"][i])!r}"/></joint>'
    for i, n in enumerate(names)
)
urdf = f'<?xml version="1.0"?><robot name="chain"><link name="l0"/>{links}{joints}</robot>'
scene = core.Scene("chain", core.loadUrdfSceneDescriptionFromXml(urdf))
scene.addGroup("all", names)
with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
    f.write(peerio.joint_limits_yaml(names, spec["vmax"], spec["amax"]))
scene.importJointLimitsFromConfig(core.loadJointLimitsConfig(f.name))
Path(f.name).unlink()
topp = PathParameterizerTOPPRA(scene, "all")
options = TOPPRAOptions(dt=peerio.SAMPLE_DT)


def solve(p):
    path = core.JointPath()
    path.joint_names = names
    path.positions = list(peerio.waypoints(p, len(names)))  # a wrong size would segfault
    traj, sec = peerio.timed(topp.generate, path, options)
    t = np.array(traj.times)
    return {
        "success": True,
        "seconds": sec,
        "duration_s": float(t[-1]),
        "samples": {"t": t, "q": np.array(traj.positions)},
    }


peerio.write(
    out,
    peer="roboplan",
    dist="roboplan",
    stage="topp",
    results=peerio.solve_all(spec["problems"], solve),
    notes="roboplan TOPP-RA, Hermite spline mode (stops at every waypoint); the 100 Hz "
    "sampling is inside the timed call",
)
