"""Small problem files for testing the peer runners, and a sanity check of their results.

Runs in the development venv (pinocchio + coal), not in a peer venv:

    /work/venv/bin/python bench/peers/make_test_problems.py generate [DIR]   # ik/plan/topp.json
    python3 bench/peers/run_peers.py DIR                                      # every runner
    /work/venv/bin/python bench/peers/make_test_problems.py check DIR        # verify results

These are NOT the benchmark's problems (bench/problems.py writes those); they only exercise the
runners: IK targets are FK of random in-limit configurations (seed = mid-range), plans are
start/goal pairs that are collision-free (self and scene, SRDF pairs disabled) with the straight
line between them blocked where possible, TOPP waypoints are random in-limit configurations.
"""

from __future__ import annotations

import argparse
import glob
import itertools
import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
import pinocchio as pin

ROOT = Path(__file__).resolve().parents[2]
URDF = ROOT / "robots/generated/KR60.urdf"
SRDF = ROOT / "robots/generated/KR60.srdf"
# Acceleration estimates of KR60.joint_limits.yaml (the URDF carries only velocities).
AMAX = [6.11, 1.2, 1.4, 17.6, 15.0, 16.9]
TIP = "tool0"

SCENES = {
    "table": [
        {
            "name": "top",
            "type": "box",
            "size": [0.8, 1.6, 0.08],
            "xyz": [1.7, 0.0, 0.9],
            "quat_wxyz": [1, 0, 0, 0],
        },
    ],
    "posts": [
        {
            "name": "post",
            "type": "cylinder",
            "radius": 0.15,
            "length": 1.6,
            "xyz": [1.3, -0.9, 0.8],
            "quat_wxyz": [1, 0, 0, 0],
        },
        {
            "name": "ball",
            "type": "sphere",
            "radius": 0.25,
            "xyz": [0.2, 1.4, 1.3],
            "quat_wxyz": [1, 0, 0, 0],
        },
        {
            "name": "crate",
            "type": "box",
            "size": [0.5, 0.5, 0.5],
            "xyz": [-1.3, 0.6, 0.6],
            "quat_wxyz": [math.cos(0.3), 0, 0, math.sin(0.3)],
        },
    ],
}


def model():
    m = pin.buildModelFromUrdf(str(URDF))
    return m, m.createData()


def joint_info(m):
    names = [n for n in m.names[1:]]
    return names, m.lowerPositionLimit.tolist(), m.upperPositionLimit.tolist()


def tool_pose(m, d, q) -> pin.SE3:
    pin.framesForwardKinematics(m, d, np.asarray(q, float))
    return d.oMf[m.getFrameId(TIP)]


def quat_wxyz(rot) -> list[float]:
    c = pin.Quaternion(rot).coeffs()  # x, y, z, w
    return [float(c[3]), float(c[0]), float(c[1]), float(c[2])]


class Collider:
    """Robot (SRDF-filtered self pairs) + one scene's obstacles, pinocchio + coal."""

    def __init__(self, m, scene: list[dict]):
        import coal

        self.m = m
        self.gm = pin.buildGeomFromUrdf(m, str(URDF), pin.GeometryType.COLLISION)
        n_robot = len(self.gm.geometryObjects)
        self.gm.addAllCollisionPairs()
        pin.removeCollisionPairs(m, self.gm, str(SRDF))
        for ob in scene:
            if ob["type"] == "box":
                shape = coal.Box(*ob["size"])
            elif ob["type"] == "cylinder":
                shape = coal.Cylinder(ob["radius"], ob["length"])
            else:
                shape = coal.Sphere(ob["radius"])
            w, x, y, z = ob["quat_wxyz"]
            place = pin.SE3(
                pin.Quaternion(w, x, y, z).normalized().matrix(), np.array(ob["xyz"], float)
            )
            gid = self.gm.addGeometryObject(
                pin.GeometryObject(ob.get("name", "ob"), 0, place, shape)
            )
            for i in range(n_robot):
                self.gm.addCollisionPair(pin.CollisionPair(i, gid))
        self.d = m.createData()
        self.gd = pin.GeometryData(self.gm)

    def collides(self, q) -> bool:
        return bool(
            pin.computeCollisions(self.m, self.d, self.gm, self.gd, np.asarray(q, float), True)
        )

    def segment_collides(self, a, b, step=0.02) -> bool:
        a, b = np.asarray(a, float), np.asarray(b, float)
        n = max(2, int(np.ceil(np.max(np.abs(b - a)) / step)) + 1)
        return any(self.collides(a + (b - a) * s) for s in np.linspace(0, 1, n))


def generate(out: Path, n_ik: int, n_plan: int, n_topp: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    m, d = model()
    names, lo, hi = joint_info(m)
    lo_a, hi_a = np.array(lo), np.array(hi)
    mid = ((lo_a + hi_a) / 2).tolist()
    vmax = m.velocityLimit.tolist()
    out.mkdir(parents=True, exist_ok=True)

    def rand_q():
        return rng.uniform(lo_a + 0.05, hi_a - 0.05)

    # IK -------------------------------------------------------------------------------------
    free = Collider(m, [])
    problems = []
    while len(problems) < n_ik:
        q = rand_q()
        if free.collides(q):  # keep targets reachable without self-collision
            continue
        t = tool_pose(m, d, q)
        problems.append(
            {
                "id": len(problems),
                "xyz": t.translation.tolist(),
                "quat_wxyz": quat_wxyz(t.rotation),
                "seed": mid,
                "q_true": q.tolist(),
            }
        )
    ik = {
        "stage": "ik",
        "robot": "KR60",
        "urdf": str(URDF),
        "srdf": str(SRDF),
        "base_link": "base_link",
        "tip_link": TIP,
        "joint_names": names,
        "lower": lo,
        "upper": hi,
        "tolerance": {"position_m": 1e-4, "orientation_rad": 1e-3},
        "timeout_s": 0.005,
        "opw": opw_parameters(m, d),
        "problems": problems,
    }
    _dump(out / "ik.json", ik)

    # plan -----------------------------------------------------------------------------------
    problems = []
    per_scene = {k: Collider(m, v) for k, v in SCENES.items()}
    for i in range(n_plan):
        name = list(SCENES)[i % len(SCENES)]
        c = per_scene[name]
        best = None
        for _ in range(400):
            a, b = rand_q(), rand_q()
            if c.collides(a) or c.collides(b):
                continue
            best = (a, b)
            if c.segment_collides(a, b):  # prefer pairs whose straight line is blocked
                break
        problems.append(
            {
                "id": i,
                "scene": name,
                "start": best[0].tolist(),
                "goal": best[1].tolist(),
                "seed": int(7 + i),
            }
        )
    plan = {
        "stage": "plan",
        "robot": "KR60",
        "urdf": str(URDF),
        "srdf": str(SRDF),
        "base_link": "base_link",
        "tip_link": TIP,
        "group": "manipulator",
        "joint_names": names,
        "lower": lo,
        "upper": hi,
        "vmax": vmax,
        "amax": AMAX,
        "scenes": SCENES,
        "time_limit_s": 2.0,
        "problems": problems,
    }
    _dump(out / "plan.json", plan)

    # topp -----------------------------------------------------------------------------------
    problems = [
        {"id": i, "waypoints": [rand_q().tolist() for _ in range(int(rng.integers(2, 7)))]}
        for i in range(n_topp)
    ]
    _dump(
        out / "topp.json",
        {
            "stage": "topp",
            "robot": "KR60",
            "joint_names": names,
            "vmax": vmax,
            "amax": AMAX,
            "problems": problems,
        },
    )
    print(out)


def opw_parameters(m, d) -> dict:
    """OPW parameters of the arm measured at q = 0 (approximate: the KR60 wrist axes miss each
    other by ~2 mm and the elbow sits 4 mm off; FK of py-opw-kinematics with these is within
    6 mm of the URDF), in py-opw-kinematics' convention: at OPW zero every link points up, the
    axes are +z, +y, +y, +x, +y, +x; a URDF axis pointing the other way is a flipped axis.
    ``base_pose``: the OPW base frame (foot of axis 1) in base_link; ``tool_pose``: tool0 in
    OPW's end frame (identity here: OPW's frame is tool0's convention, z out of the flange)."""
    q0 = pin.neutral(m)
    pin.forwardKinematics(m, d, q0)
    pin.updateFramePlacements(m, d)
    p = [d.oMi[j].translation.copy() for j in range(1, 7)]
    axes = []
    for j in range(1, 7):
        jm = m.joints[j]
        local = {
            "JointModelRX": [1, 0, 0],
            "JointModelRY": [0, 1, 0],
            "JointModelRZ": [0, 0, 1],
        }.get(jm.shortname(), None)
        local = np.array(local if local is not None else jm.extract().axis, float)
        axes.append(d.oMi[j].rotation @ local)
    # wrist centre: point nearest to axes 4, 5, 6 (least squares)
    A = np.zeros((3, 3))
    rhs = np.zeros(3)
    for w, pt in zip(axes[3:], p[3:], strict=True):
        P = np.eye(3) - np.outer(w, w)
        A += P
        rhs += P @ pt
    wc = np.linalg.solve(A, rhs)
    tool = tool_pose(m, d, q0)
    foot = np.array([p[0][0], p[0][1], 0.0])
    opw_axes = [[0, 0, 1], [0, 1, 0], [0, 1, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0]]
    flip = [bool(np.dot(a, b) < 0) for a, b in zip(axes, opw_axes, strict=True)]
    return {
        "a1": float(p[1][0] - foot[0]),
        "a2": float(-(wc[2] - p[2][2])),
        "b": float(wc[1] - foot[1]),
        "c1": float(p[1][2]),
        "c2": float(np.hypot(p[2][0] - p[1][0], p[2][2] - p[1][2])),
        "c3": float(wc[0] - p[2][0]),
        "c4": float(tool.translation[0] - wc[0]),
        # py-opw's zero pose has the forearm along the upper arm; ours has it across.
        "offsets": [0.0, 0.0, -math.pi / 2 if flip[2] else math.pi / 2, 0.0, 0.0, 0.0],
        "flip_axes": flip,
        "base_pose": {"xyz": foot.tolist(), "quat_wxyz": [1.0, 0.0, 0.0, 0.0]},
        "tool_pose": {"xyz": [0.0, 0.0, 0.0], "quat_wxyz": [1.0, 0.0, 0.0, 0.0]},
        "note": "measured at q=0 by make_test_problems.py; approximate (wrist offset)",
    }


def _dump(path: Path, doc: dict) -> None:
    path.write_text(json.dumps(doc, indent=1) + "\n")


# ------------------------------------------------------------------------------------------
def check(dirpath: Path) -> int:
    m, d = model()
    bad = 0
    for res_path in sorted(glob.glob(str(dirpath / "*_*.json"))):
        res = json.loads(Path(res_path).read_text())
        stage = res.get("stage")
        if stage not in ("ik", "plan", "topp"):
            continue
        spec = json.loads((dirpath / f"{stage}.json").read_text())
        probs = {p["id"]: p for p in spec["problems"]}
        line = {"ik": check_ik, "plan": check_plan, "topp": check_topp}[stage](
            m, d, spec, probs, res
        )
        print(f"{res['peer']:>9} {res['version']:<7} {stage:<4} {line}")
        bad += line.startswith("FAIL")
    return 1 if bad else 0


def _stats(results):
    ok = [r for r in results if r.get("success")]
    secs = [r["seconds"] for r in ok if r.get("seconds") is not None]
    errs = sum("error" in r for r in results)
    return (
        ok,
        (
            f"{len(ok)}/{len(results)} ok, mean {1e3 * np.mean(secs):.3f} ms, "
            f"median {1e3 * np.median(secs):.3f} ms"
            if secs
            else f"0/{len(results)} ok"
        ),
        errs,
    )


def check_ik(m, d, spec, probs, res):
    ok, head, errs = _stats(res["results"])
    tol = spec["tolerance"]
    lo, hi = np.array(spec["lower"]), np.array(spec["upper"])
    within, worst_p, worst_o, out_of_limits = 0, 0.0, 0.0, 0
    for r in ok:
        p = probs[r["id"]]
        t = tool_pose(m, d, r["q"])
        dp = float(np.linalg.norm(t.translation - np.array(p["xyz"])))
        w, x, y, z = p["quat_wxyz"]
        target = pin.Quaternion(w, x, y, z).normalized().matrix()
        do = float(np.linalg.norm(pin.log3(target.T @ t.rotation)))
        worst_p, worst_o = max(worst_p, dp), max(worst_o, do)
        q = np.array(r["q"])
        lim = bool(np.all(q >= lo - 1e-6) and np.all(q <= hi + 1e-6))
        out_of_limits += not lim
        within += dp <= tol["position_m"] * 1.01 and do <= tol["orientation_rad"] * 1.01 and lim
    verdict = "ok  " if ok and within == len(ok) else "NOTE" if ok else "FAIL"
    return (
        f"{verdict} {head}; {within}/{len(ok)} verified within tolerance and limits "
        f"(worst {1e3 * worst_p:.3f} mm, {1e3 * worst_o:.3f} mrad, {out_of_limits} outside limits)"
        f"; {errs} errors"
    )


def check_plan(m, d, spec, probs, res):
    ok, head, errs = _stats(res["results"])
    colliders = {k: Collider(m, v) for k, v in spec["scenes"].items()}
    lo, hi = np.array(spec["lower"]), np.array(spec["upper"])
    ends_ok, free_ok, n_way = 0, 0, []
    for r in ok:
        p = probs[r["id"]]
        path = np.array(r["path"])
        n_way.append(len(path))
        ends_ok += bool(
            np.allclose(path[0], p["start"], atol=1e-6)
            and np.allclose(path[-1], p["goal"], atol=1e-6)
        )
        c = colliders[p["scene"]]
        inside = bool(np.all(path >= lo - 1e-6) and np.all(path <= hi + 1e-6))
        free_ok += inside and not any(
            c.segment_collides(a, b, 0.01) for a, b in itertools.pairwise(path)
        )
    durs = [r["duration_s"] for r in ok if r.get("duration_s") is not None]
    verdict = "ok  " if ok and ends_ok == free_ok == len(ok) else "NOTE" if ok else "FAIL"
    return (
        f"{verdict} {head}; ends match {ends_ok}/{len(ok)}; collision-free & in limits "
        f"(our check, 0.01 rad steps) {free_ok}/{len(ok)}; "
        f"waypoints {np.mean(n_way) if n_way else 0:.1f}; "
        f"mean duration {np.mean(durs) if durs else float('nan'):.2f} s; {errs} errors"
    )


def check_topp(m, d, spec, probs, res):
    ok, head, errs = _stats(res["results"])
    vmax, amax = np.array(spec["vmax"]), np.array(spec["amax"])
    ends_ok, vr, ar = 0, 0.0, 0.0
    for r in ok:
        wp = np.array(probs[r["id"]]["waypoints"])
        t, q = np.array(r["samples"]["t"]), np.array(r["samples"]["q"])
        ends_ok += bool(
            np.allclose(q[0], wp[0], atol=1e-4)
            and np.allclose(q[-1], wp[-1], atol=1e-4)
            and abs(t[-1] - r["duration_s"]) < 1e-6
            and t[0] == 0
        )
        dt = np.diff(t)
        v = np.diff(q, axis=0) / dt[:, None]
        vr = max(vr, float(np.max(np.abs(v) / vmax)))
        if len(v) > 2:
            a = np.diff(v, axis=0) / ((dt[1:] + dt[:-1]) / 2)[:, None]
            ar = max(ar, float(np.max(np.abs(a) / amax)))
    durs = [r["duration_s"] for r in ok]
    verdict = (
        "ok  "
        if ok and ends_ok == len(ok) and vr < 1.02 and ar < 1.05
        else "NOTE"
        if ok
        else "FAIL"
    )
    return (
        f"{verdict} {head}; ends match {ends_ok}/{len(ok)}; max |v|/vmax {vr:.3f}, "
        f"max |a|/amax (finite differences) {ar:.3f}; "
        f"mean duration {np.mean(durs) if durs else float('nan'):.2f} s; {errs} errors"
    )


def main() -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = ap.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("generate", help="write ik.json, plan.json, topp.json")
    g.add_argument("dir", nargs="?", help="output folder (default: a new temp dir)")
    g.add_argument("--ik", type=int, default=50)
    g.add_argument("--plan", type=int, default=8)
    g.add_argument("--topp", type=int, default=10)
    g.add_argument("--seed", type=int, default=0)
    c = sub.add_parser("check", help="verify the <peer>_<stage>.json results in a folder")
    c.add_argument("dir")
    a = ap.parse_args()
    if a.cmd == "generate":
        out = Path(a.dir) if a.dir else Path(tempfile.mkdtemp(prefix="peer-problems-"))
        generate(out, a.ik, a.plan, a.topp, a.seed)
        return 0
    return check(Path(a.dir))


if __name__ == "__main__":
    sys.exit(main())
