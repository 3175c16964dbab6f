"""Collision stage: is the KR60 in collision (itself, SRDF pairs disabled, and the scene) at a
configuration? Uniformly random in-limit configurations in ``table`` and in the ``boxes_N``
scenes (N = 1, 10, 100, 1000: how the cost grows with the number of obstacles); usar-arm beside
mplib and roboplan.

As a solver (our side)::

    python bench/collision.py --api single|many PROBLEMS.json RESULTS.json

``single``: ``CollisionWorld.in_collision(q)`` timed per configuration. ``many``:
``CollisionWorld.in_collision_many(Q)`` over blocks of :data:`BATCH` configurations of a scene;
a configuration's time is its block's time / the block size (s per configuration).

Every answer is compared with the brute-force python-fcl judge (``verify.Judge``): an answer
that differs from it (a missed or an invented contact) is not a success.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

import common
import numpy as np
from common import Context, peerio
from scenes import from_json as scene_from_json
from tesseract_config import with_tesseract
from verify import Judge

from usar_arm.planning.robot import robot_from_files

BATCH = 100
"""Configurations per ``in_collision_many`` call (an edge of ~1 rad at 0.01 rad steps)."""
WARMUP = 3
"""Configurations checked once, untimed, at the start of every scene, through the API that is
timed: the peers' collision runners warm up the same way (``solve_by_scene(warmup=3)``)."""


def _worlds(spec: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
    robot = robot_from_files(spec["urdf"], spec["srdf"])
    return robot, {name: robot.collision_world(scene_from_json(name, items))
                   for name, items in spec["scenes"].items()}


def _rotation_angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle (rad) of the rotation between the 3x3 rotations ``a`` and ``b``:
    ||a - b||_F = 2 sqrt(2) sin(angle / 2), accurate near 0 (where acos of the trace is not)."""
    return 2.0 * float(np.arcsin(min(1.0, float(np.linalg.norm(a - b)) / np.sqrt(8.0))))


def _by_scene(problems: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    groups: dict[str, list[dict[str, Any]]] = {}
    for p in problems:
        groups.setdefault(p["scene"], []).append(p)
    return groups


def solver_main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--api", choices=("single", "many"), default="single")
    ap.add_argument("problems")
    ap.add_argument("results")
    a = ap.parse_args(argv)
    spec = common.read_json(common.Path(a.problems))
    _, worlds = _worlds(spec)
    results: list[dict[str, Any]] = []
    for name, group in _by_scene(spec["problems"]).items():
        world = worlds[name]
        qs = np.array([p["q"] for p in group], float)
        if a.api == "single":  # warm-up in every scene, as the peers (peerio.solve_by_scene)
            for q in qs[:WARMUP]:
                world.in_collision(q)
        else:
            world.in_collision_many(qs[:WARMUP])
        if a.api == "single":
            for p, q in zip(group, qs, strict=True):
                hit, sec = peerio.timed(world.in_collision, q)
                results.append({"id": p["id"], "success": True, "seconds": sec,
                                "collision": bool(hit)})
        else:
            for lo in range(0, len(group), BATCH):
                hits, sec = peerio.timed(world.in_collision_many, qs[lo:lo + BATCH])
                for p, hit in zip(group[lo:lo + BATCH], hits, strict=True):
                    results.append({"id": p["id"], "success": True,
                                    "seconds": sec / len(hits), "collision": bool(hit)})
    results.sort(key=lambda r: r["id"])
    peerio.write(a.results, peer=f"usar-arm ({a.api})", dist="usar-arm", stage="collision",
                 results=results,
                 settings={"api": "CollisionWorld.in_collision(q)" if a.api == "single" else
                           f"CollisionWorld.in_collision_many, blocks of {BATCH}"})
    return 0


# ------------------------------------------------------------------------------ the stage
def run(ctx: Context) -> dict[str, Any]:
    """Run the collision cases (one per scene) and return the stage document."""
    started = time.perf_counter()
    path, spec = ctx.problem("collision_KR60")
    spec = with_tesseract(spec, ctx.work)
    solvers = [common.ours("usar-arm", "collision.py", "--api", "single",
                           note="CollisionWorld.in_collision(q), one call per configuration"),
               common.ours("usar-arm batch", "collision.py", "--api", "many",
                           note=f"CollisionWorld.in_collision_many, {BATCH} per call"),
               ctx.peer("mplib", "collision", "robot.set_qpos + is_state_colliding (FCL)"),
               ctx.peer("roboplan", "collision", "scene.hasCollisions (coal)"),
               ctx.peer("tesseract", "collision", "setState + contactTest (Bullet, the "
                        "config's default manager); tool0 FK (position and rotation) "
                        "compared with the judge's")]
    outcomes = common.run_alternating(spec, solvers, ctx.work, ctx.rounds, "collision_KR60")
    cases: dict[str, Any] = {}
    for name, group in _by_scene(spec["problems"]).items():
        judge = Judge.for_scene(spec, name)
        truth = judge.colliding(np.array([p["q"] for p in group], float))
        truth_of = {p["id"]: bool(t) for p, t in zip(group, truth, strict=True)}

        def check(p: dict[str, Any], r: dict[str, Any], truth_of: dict[Any, bool] = truth_of,
                  judge: Judge = judge) -> dict[str, Any]:
            t = truth_of[p["id"]]
            answer = r.get("collision") if r.get("success") else None
            row = {"verified": answer is not None and answer == t, "collision": answer,
                   "truth": t}
            if r.get("tool0") is not None:  # a peer's FK of tool0, against the judge's
                judge.kin.update(np.array(p["q"], float))
                ours, theirs = judge.kin.frame("tool0"), np.array(r["tool0"])
                row["fk_error_m"] = float(np.linalg.norm(ours[:3, 3] - theirs[:3, 3]))
                row["fk_error_rad"] = _rotation_angle(ours[:3, :3], theirs[:3, :3])
            return row

        def extra(raw: dict[str, list[Any]]) -> dict[str, Any]:
            pairs = list(zip(raw["collision"], raw["truth"], strict=True))
            fk = [e for e in raw.get("fk_error_m", []) if e is not None]
            fk_rad = [e for e in raw.get("fk_error_rad", []) if e is not None]
            return {"false_negatives": sum(1 for a, t in pairs if a is False and t),
                    "false_positives": sum(1 for a, t in pairs if a is True and not t),
                    "colliding_fraction": float(np.mean(raw["truth"])) if pairs else None,
                    **({"fk_max_error_m": max(fk)} if fk else {}),
                    **({"fk_max_error_rad": max(fk_rad)} if fk_rad else {})}

        sub = {**spec, "problems": group}
        ids = set(truth_of)
        cases[name] = {"scene": name, "obstacles": len(spec["scenes"][name]),
                       **common.build_case(path, sub, common.subset(outcomes, ids), check,
                                           extra)}
    return common.stage_document("collision", ctx.mode, {"rounds": ctx.rounds, "batch": BATCH,
                                                         "judge": "verify.Judge"},
                                 cases, _targets(cases), started)


def _targets(cases: dict[str, Any]) -> list[dict[str, Any]]:
    out = []
    for solver, label in (("usar-arm", "in_collision"), ("usar-arm batch", "in_collision_many")):
        s = cases["table"]["solvers"][solver].get("summary", {})
        out.append(common.target(f"Collision KR60 in table, mean per configuration ({label})",
                                 (s.get("time_all_s") or {}).get("mean"), 30e-6, "<=", "s"))
        out.append(common.target(f"Collision KR60 in table, agreement with the brute-force "
                                 f"judge ({label})", s.get("success_rate"), 1.0, ">=",
                                 "fraction"))
    solvers = cases["table"]["solvers"]

    def times(solver: str) -> dict[str, Any]:
        return solvers.get(solver, {}).get("summary", {}).get("time_all_s") or {}

    single, batch = times("usar-arm").get("median"), times("usar-arm batch").get("mean")
    peer = times("roboplan").get("median")
    out.append(common.target("Collision KR60 in table, median single query / roboplan's median "
                             "(same run)", single / peer if single and peer else None, 1.0,
                             "<=", "ratio", "" if peer else "roboplan not run"))
    out.append(common.target("Collision KR60 in table, batched, mean per configuration",
                             batch, 2e-6, "<=", "s"))
    return out


if __name__ == "__main__":
    sys.exit(solver_main())
