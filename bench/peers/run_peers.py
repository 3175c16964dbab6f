#!/usr/bin/env python3
"""Run every peer runner on the problem files of a folder (stdlib only).

    python3 bench/peers/run_peers.py DIR [--only mplib,roboplan] [--stages ik,plan]

For each bench/peers/run_<peer>_<stage>.py whose DIR/<stage>.json exists, runs
bench/.venvs/<peer>/bin/python run_<peer>_<stage>.py DIR/<stage>.json DIR/<peer>_<stage>.json
(creates nothing: make the venvs first with venvs.py). Exits non-zero if a runner failed.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import venvs

HERE = Path(__file__).resolve().parent


def runners() -> list[tuple[str, str, Path]]:
    out = []
    for f in sorted(HERE.glob("run_*_*.py")):
        if f.name == "run_peers.py":
            continue
        peer, stage = f.stem[len("run_") :].rsplit("_", 1)
        out.append((peer, stage, f))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("dir", type=Path)
    ap.add_argument("--only", help="comma-separated peers")
    ap.add_argument("--stages", help="comma-separated stages (ik, plan, topp)")
    a = ap.parse_args()
    only = set(a.only.split(",")) if a.only else None
    stages = set(a.stages.split(",")) if a.stages else None
    failed = []
    for peer, stage, script in runners():
        problems = a.dir / f"{stage}.json"
        if (
            (only and peer not in only)
            or (stages and stage not in stages)
            or not problems.is_file()
        ):
            continue
        py = venvs.python_path(peer)
        if not venvs.is_ready(peer):
            print(
                f"[run_peers] {peer}: no venv at {py.parent.parent} "
                f"(python3 bench/peers/venvs.py --only {peer})",
                file=sys.stderr,
            )
            failed.append(f"{peer}_{stage}")
            continue
        cmd = [str(py), str(script), str(problems), str(a.dir / f"{peer}_{stage}.json")]
        print(f"[run_peers] {' '.join(cmd)}", file=sys.stderr, flush=True)
        if subprocess.run(cmd).returncode != 0:
            failed.append(f"{peer}_{stage}")
    if failed:
        print(f"[run_peers] failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
