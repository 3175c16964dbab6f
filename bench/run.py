"""Run the benchmarks: usar-arm beside its peers, stage by stage, on one shared problem set.

    python bench/run.py [--quick] [--stages ik,collision,plan,carry,timing,discovery,execution,
                                            calibrate,workspace,planners,ros,robots,
                                            pickplace]
                        [--out bench/results] [--problems DIR] [--rounds R] [--peers a,b]

1. Writes the problem set (``bench/problems.py``; default ``bench/problems/<quick|full>``).
2. Runs each stage: every solver (ours and each peer, each peer in its own venv
   ``bench/.venvs/<peer>``, see ``bench/peers/venvs.py``) on the same problem files, in
   ``R`` alternating rounds; checks every answer with the same checks; writes
   ``<out>/<stage>.json``.
3. Writes ``<out>/README.md`` and the PNG plots (``bench/report.py``).

Peers whose venv is missing are reported as skipped, with the reason. ``--quick`` runs a few
problems per stage (the CI smoke run, about two minutes); the full run takes under 30 minutes
on two cores. Progress goes to stderr; the exit code is 0 unless the harness itself failed
(missed targets are results, not errors).
"""

from __future__ import annotations

import argparse
import importlib
import shutil
import sys
import tempfile
import time
import traceback
from pathlib import Path
from typing import Any

import common
import problems as problem_sets

STAGES = ("ik", "collision", "plan", "carry", "timing", "discovery", "execution", "calibrate",
          "workspace", "planners", "ros", "robots", "pickplace")
MODULES = {"ik": "ik", "collision": "collision", "plan": "plan", "carry": "carry",
           "timing": "timing", "discovery": "discovery", "execution": "execution",
           "calibrate": "calibrate", "workspace": "workspace", "planners": "planners",
           "ros": "ros", "robots": "robots", "pickplace": "pick_place"}
ROUNDS = {"quick": 1, "full": 3}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a few problems per stage (CI)")
    ap.add_argument("--stages", default=",".join(STAGES),
                    help=f"comma-separated, from {', '.join(STAGES)}")
    ap.add_argument("--out", type=Path, default=common.BENCH / "results")
    ap.add_argument("--problems", type=Path, help="problem folder (default bench/problems/MODE)")
    ap.add_argument("--rounds", type=int, help="alternation rounds (default quick 1, full 3)")
    ap.add_argument("--peers", help="comma-separated peers to run (default: every peer)")
    ap.add_argument("--keep-work", action="store_true", help="keep the per-round files")
    a = ap.parse_args(argv)
    stages = [s.strip() for s in a.stages.split(",") if s.strip()]
    unknown = [s for s in stages if s not in STAGES]
    if unknown:
        print(f"unknown stage(s) {', '.join(unknown)}; stages: {', '.join(STAGES)}",
              file=sys.stderr)
        return 2
    mode = "quick" if a.quick else "full"
    begin = time.perf_counter()
    out: Path = a.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    sizes = problem_sets.QUICK if a.quick else problem_sets.FULL
    folder = (a.problems or common.BENCH / "problems" / mode).resolve()
    files = problem_sets.generate(sizes, folder)
    generation = time.perf_counter() - begin
    work = Path(tempfile.mkdtemp(prefix="bench-work-"))
    ctx = common.Context(mode, out, files, work, a.rounds or ROUNDS[mode],
                         frozenset(a.peers.split(",")) if a.peers else None)
    failed = []
    for stage in stages:
        common.log(f"=== stage {stage} ({mode})")
        t0 = time.perf_counter()
        try:
            module = importlib.import_module(MODULES[stage])
            doc = module.run(ctx)
        except Exception:
            traceback.print_exc()
            failed.append(stage)
            continue
        common.write_json(out / f"{stage}.json", doc)
        common.log(f"=== stage {stage} done in {time.perf_counter() - t0:.1f} s -> "
                   f"{out / f'{stage}.json'}")
    import report

    record = {
        "mode": mode, "stages": stages, "failed_stages": failed, "rounds": ctx.rounds,
        "peers": sorted(ctx.peers) if ctx.peers else "all",
        "problem_folder": str(folder), "problem_generation_seconds": generation,
        "wall_seconds_before_report": time.perf_counter() - begin,
        "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "machine": common.machine()}
    common.write_json(out / "run.json", _run_record(out / "run.json", record))
    report.generate(out, total_seconds=time.perf_counter() - begin)
    if a.keep_work:
        common.log(f"per-round files kept in {work}")
    else:
        shutil.rmtree(work, ignore_errors=True)
    common.log(f"done in {time.perf_counter() - begin:.1f} s; results in {out}"
               + (f"; FAILED stages: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


def _run_record(path: Path, record: dict[str, Any]) -> dict[str, Any]:
    """What ``run.json`` keeps: a run of every stage replaces it; a run of some stages into a
    folder that holds a whole run is added to its ``later_runs`` (the report says which
    stages come from those)."""
    if set(record["stages"]) == set(STAGES) or not path.is_file():
        return record
    whole = common.read_json(path)
    if set(whole.get("stages", ())) != set(STAGES):
        return record
    return {**whole, "later_runs": [*whole.get("later_runs", []), record]}


if __name__ == "__main__":
    sys.exit(main())
