"""Discovery + URDF stage: how long ``usar_arm.description.embedded.describe`` takes to learn an
arm from the embedded simulator over TCP and build its validated description (URDF, SRDF, joint
limits, collision matrix from 10,000 samples), and how accurate that description is against the
simulator's own model. No peer does this; our figures only.

As a solver (its own process)::

    python bench/discovery.py PROBLEMS.json RESULTS.json

Each problem names a robot and a wire precision (``udk``: the UDK number format, the default;
``full``: every digit). Timed: ``run_discovery`` (the TCP exchanges), ``describe_discovered``
(frames, limits, URDF, validation, collision matrix, SRDF, and the accuracy check of
``accuracy_samples`` random configurations against the simulator's model) and
``write_description`` (atomic file writes), each separately; ``seconds`` is what a user of
``usar-arm urdf --no-calibrate`` waits for: every run in a fresh process (an empty description
cache of its own), from the process's launch (interpreter start and imports included) to the
files written. Judged, untimed: tool0 of the URDF as written (read back from the file) by the
judge's own Pinocchio model against the simulator's spec (``calibrate.tool0_errors``) at
:data:`ACCURACY_SAMPLES` seeded configurations; usar-arm's own accuracy report
(``accuracy_vs_simulator``: its FK against its reading of the spec) is kept beside it.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import common
from common import Context, peerio

from usar_arm.description.cache import robot_from_description
from usar_arm.description.embedded import describe_discovered, run_discovery
from usar_arm.description.pipeline import DescribeOptions, write_description
from usar_arm.planning.acm import compute_acm

REPEATS = {("quick", "udk"): 1, ("full", "udk"): 3, ("full", "full"): 1}
"""Runs per (mode, wire precision): the full-precision run is for its accuracy figures."""
ROBOTS = {"quick": ("KR60",), "full": ("KR60", "Fanuc_M16iB20")}
ACCURACY_SAMPLES = 1000
ACM_SAMPLES = 10_000


def solver_main(argv: list[str] | None = None) -> int:
    spec, out = peerio.args()
    cache = tempfile.mkdtemp(prefix="bench-cache-")  # a first run: nothing cached
    os.environ["USAR_ARM_CACHE"] = cache

    def solve(p: dict[str, Any]) -> dict[str, Any]:
        startup = common.since_launch()
        options = DescribeOptions(robot=p["robot"], wire_precision=p["wire_precision"],
                                  accuracy_samples=p["accuracy_samples"])
        record, t_wire = peerio.timed(run_discovery, options)
        desc, t_build = peerio.timed(describe_discovered, record, options)
        with tempfile.TemporaryDirectory() as folder:
            _, t_write = peerio.timed(write_description, desc, folder)
            command = common.since_launch()
            written = next(Path(folder).glob("*.urdf")).read_text(encoding="utf-8")
        from calibrate import tool0_errors  # the judge's imports: after the timed command

        flange_m, flange_rad = tool0_errors(written, p["robot"], p["accuracy_samples"])
        robot = robot_from_description(desc)
        _, t_acm = peerio.timed(compute_acm, robot.chain, robot.kinematics, ACM_SAMPLES)
        d = desc.discovery
        return {"success": True, "seconds": command, "startup_seconds": startup,
                "in_process_seconds": t_wire + t_build + t_write, "discovery_seconds": t_wire,
                "build_seconds": t_build,
                "write_seconds": t_write, "acm_seconds": t_acm, "dof": desc.chain.dof,
                "exchanges": len(d.get("exchanges", [])),
                "judged": {"max_flange_error_m": flange_m, "max_flange_error_rad": flange_rad,
                           "configurations": p["accuracy_samples"]},
                "accuracy": d.get("accuracy_vs_simulator"),
                "precision": {k: v for k, v in d.get("precision", {}).items()
                              if k != "snapped"},
                "collision_matrix": {k: v for k, v in d.get("collision_matrix", {}).items()
                                     if k != "checked_pairs"},
                "warnings": list(desc.warnings)}

    peerio.write(out, peer="usar-arm", dist="usar-arm", stage="discovery",
                 results=peerio.solve_all(spec["problems"], solve, warmup=0))
    shutil.rmtree(cache, ignore_errors=True)
    return 0


def run(ctx: Context) -> dict[str, Any]:
    """Time and check the descriptions of both arms at both wire precisions."""
    started = time.perf_counter()
    precisions = ("udk",) if ctx.mode == "quick" else ("udk", "full")
    problems = [{"id": i, "robot": r, "wire_precision": w, "repeat": k,
                 "accuracy_samples": ACCURACY_SAMPLES}
                for i, (r, w, k) in enumerate((r, w, k) for r in ROBOTS[ctx.mode]
                                              for w in precisions
                                              for k in range(REPEATS[ctx.mode, w]))]
    spec = {"stage": "discovery", "problems": problems}
    path = ctx.work / "discovery_problems.json"
    common.write_json(path, spec)
    solver = common.ours("usar-arm", "discovery.py",
                         note="run_discovery + describe_discovered + write_description, each "
                              "run a fresh process, timed from its launch")
    outcome = common.run_alternating(spec, [solver], ctx.work, len(problems),  # one a process
                                     "discovery")["usar-arm"]
    cases = {}
    for robot in ROBOTS[ctx.mode]:
        for wire in precisions:
            rows = [(p, r) for p, r in zip(problems, outcome.results, strict=True)
                    if p["robot"] == robot and p["wire_precision"] == wire]
            results = [r for _, r in rows]
            ok = [bool(r.get("success")) for r in results]
            summary = common.base_summary(results, ok)
            for key in ("startup_seconds", "in_process_seconds", "discovery_seconds",
                        "build_seconds", "write_seconds", "acm_seconds"):
                summary[key] = common.stats([r.get(key) for r in results])
            last = next((r for r in reversed(results) if r.get("success")), {})
            summary.update(judged=_worst_judged(results),
                           accuracy=last.get("accuracy"), precision=last.get("precision"),
                           collision_matrix=last.get("collision_matrix"),
                           warnings=last.get("warnings"), dof=last.get("dof"))
            raw = {k: [r.get(k) for r in results]
                   for k in ("id", "success", "seconds", "startup_seconds", "discovery_seconds",
                             "build_seconds", "write_seconds", "acm_seconds")}
            cases[f"{robot} ({wire})"] = {
                "robot": robot, "wire_precision": wire,
                "problems": {"file": None, "count": len(results),
                             "settings": {"accuracy_samples": ACCURACY_SAMPLES,
                                          "acm_samples": DescribeOptions().acm_samples}},
                "solvers": {"usar-arm": common.solver_record(outcome, raw, summary)},
                "ratios": {}}
    return common.stage_document("discovery", ctx.mode,
                                 {"repeats": {w: REPEATS[ctx.mode, w] for w in precisions},
                                  "precisions": list(precisions)},
                                 cases, _targets(cases), started)


def _worst_judged(results: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The judge's largest tool0 errors (m, rad) over a case's runs; None when none ran."""
    judged = [r["judged"] for r in results if r.get("judged")]
    if not judged:
        return None
    return {"max_flange_error_m": max(j["max_flange_error_m"] for j in judged),
            "max_flange_error_rad": max(j["max_flange_error_rad"] for j in judged),
            "configurations": judged[0]["configurations"], "runs": len(judged),
            "how": "the judge's Pinocchio model of the URDF as written against the simulator's "
                   "spec (tool0_by_spec)"}


def _targets(cases: dict[str, Any]) -> list[dict[str, Any]]:
    kr60 = cases.get("KR60 (udk)", {}).get("solvers", {}).get("usar-arm", {}).get("summary", {})
    return [common.target(f"SRDF collision matrix from {ACM_SAMPLES:,} sampled states (KR60), "
                          "median", (kr60.get("acm_seconds") or {}).get("median"), 2.0, "<=",
                          "s", "compute_acm, timed on its own after the description")]


if __name__ == "__main__":
    sys.exit(solver_main())
