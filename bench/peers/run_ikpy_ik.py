"""IK with ikpy 4.2.1: python run_ikpy_ik.py PROBLEMS.json RESULTS.json

Chain: Chain.from_urdf_file(urdf, base_elements=<the explicit link/joint path base -> tip>,
active_links_mask=<revolute/prismatic joints>) - the explicit path is needed because ikpy
follows the first child otherwise, and base_link/link_6 here have more than one.
Timed: chain.inverse_kinematics(xyz, R, orientation_mode="all", initial_position=seed) with the
defaults otherwise (scipy least_squares, numpy backend; ikpy has no timeout). ikpy always
returns a configuration: success = its own FK of the answer is within the problem's tolerance
(checked after the timed call).
"""

import warnings

import numpy as np
import peerio
from ikpy.chain import Chain

spec, out = peerio.args()
tol = spec["tolerance"]
path = peerio.chain_path(spec["urdf"], spec["base_link"], spec["tip_link"])
elements = [spec["base_link"]] + [e for name, _, child in path for e in (name, child)]
mask = [False] + [kind != "fixed" for _, kind, _ in path]
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    chain = Chain.from_urdf_file(spec["urdf"], base_elements=elements, active_links_mask=mask)
chain_names = [link.name for link, active in zip(chain.links, mask, strict=True) if active]
names = spec["joint_names"]


def solve(p):
    init = chain.active_to_full(
        peerio.reorder(p["seed"], names, chain_names), [0.0] * len(chain.links)
    )
    rot = peerio.quat_to_matrix(p["quat_wxyz"])
    full, sec = peerio.timed(
        chain.inverse_kinematics,
        np.array(p["xyz"]),
        rot,
        orientation_mode="all",
        initial_position=init,
    )
    fk = chain.forward_kinematics(full)
    dp = float(np.linalg.norm(fk[:3, 3] - np.array(p["xyz"])))
    cos = (np.trace(rot.T @ fk[:3, :3]) - 1) / 2
    do = float(np.arccos(np.clip(cos, -1.0, 1.0)))
    ok = dp <= tol["position_m"] and do <= tol["orientation_rad"]
    q = peerio.reorder(chain.active_from_full(full), chain_names, names)
    return {
        "success": ok,
        "seconds": sec,
        "q": q if ok else None,
        "residual": {"position_m": dp, "orientation_rad": do},
        **({} if ok else {"q_best": q}),
    }


peerio.write(
    out,
    peer="ikpy",
    dist="ikpy",
    stage="ik",
    results=peerio.solve_all(spec["problems"], solve),
    notes="success judged by ikpy's own FK against the tolerance (ikpy has no success flag)",
)
