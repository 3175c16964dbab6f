"""Shared pieces of the benchmark harness: paths, the machine and version record, statistics,
JSON output, and running solvers (ours and the peers) in alternation over the same problems.

Every solver, ours included, runs in its own process as ``PYTHON SCRIPT PROBLEMS.json
RESULTS.json`` and writes the peer results format of ``bench/README-peers.md``. A problem set is
split into ``rounds`` interleaved chunks; each round runs every solver once on its chunk, the
starting solver rotating from round to round, so that a noisy machine slows every solver alike.
Times are seconds (``time.perf_counter``) unless a name says otherwise.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "bench"
PEERS_DIR = BENCH / "peers"
if str(PEERS_DIR) not in sys.path:
    sys.path.insert(0, str(PEERS_DIR))

import peerio  # noqa: E402  (bench/peers, stdlib + numpy)
import venvs  # noqa: E402

OUR_DISTS = ("usar-arm", "numpy", "scipy", "pin", "python-fcl", "ompl", "ruckig", "mujoco")
ENVIRONMENT = {"PYTHONHASHSEED": "0", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
               "MKL_NUM_THREADS": "1"}
"""Set for every solver process. One BLAS thread: on two cores OpenBLAS's worker threads keep
spinning after a batched numpy call and doubled our single-call collision check (115 -> 200 us)
in a measurement; peers that start their own threads (TRAC-IK) are unaffected."""
RUNNER_TIMEOUT_S = 1800.0
"""A solver process that runs longer than this on one chunk is stopped and its chunk failed."""


def log(msg: str) -> None:
    """Progress on stderr (results go to files)."""
    print(f"[bench {time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------------------ the machine
def machine() -> dict[str, Any]:
    """CPU model, logical cores, RAM (GiB), Python, OS and the load average when asked."""
    cpu = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    ram = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                ram = round(int(line.split()[1]) / 2**20, 1)
    except OSError:
        pass
    load = list(os.getloadavg()) if hasattr(os, "getloadavg") else None
    return {"cpu": cpu, "logical_cores": os.cpu_count(), "ram_gib": ram,
            "python": platform.python_version(), "os": platform.platform(),
            "load_average_1_5_15": load}


def versions(dists: Iterable[str] = OUR_DISTS) -> dict[str, str]:
    """Installed versions of ``dists`` in this interpreter."""
    return {d: peerio.version(d) for d in dists}


def sha256(path: Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


# ------------------------------------------------------------------------------ statistics
def stats(values: Sequence[float | None]) -> dict[str, float | None]:
    """median, p90, p99, mean, min, max of the non-null values (None when there are none)."""
    v = np.array([x for x in values if x is not None], float)
    if v.size == 0:
        return {k: None for k in ("median", "p90", "p99", "mean", "min", "max")}
    return {"median": float(np.median(v)), "p90": float(np.percentile(v, 90)),
            "p99": float(np.percentile(v, 99)), "mean": float(v.mean()),
            "min": float(v.min()), "max": float(v.max())}


def ratio(ours: float | None, peer: float | None) -> float | None:
    """ours / peer, or None when either is missing or the peer's figure is 0."""
    if ours is None or peer is None or peer == 0:
        return None
    return ours / peer


def plain(x: Any, digits: int = 7) -> Any:
    """A JSON-safe copy: numpy to Python, NaN/inf to null, floats to ``digits`` significant
    digits (the raw figures are long lists; 7 digits keep 0.1 us of a millisecond)."""
    if isinstance(x, dict):
        return {str(k): plain(v, digits) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [plain(v, digits) for v in x]
    if isinstance(x, np.ndarray):
        return plain(x.tolist(), digits)
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        f = float(x)
        return float(f"{f:.{digits}g}") if math.isfinite(f) else None
    return x


PROBLEM_DIGITS = 17
"""Significant digits of the problem files the solvers read: every float round-trips, so a
solver answers exactly the configuration the judge judges (at 7 digits a q moved by up to
1e-6 rad: a "boundary" configuration 1e-6 rad past a contact was handed to every solver on the
free side while the judge judged it in contact)."""


def write_json(path: Path, doc: dict[str, Any], indent: int | None = 1, digits: int = 7) -> None:
    """Write ``doc`` atomically (temp file + rename), compact lists of numbers, floats to
    ``digits`` significant digits (:data:`PROBLEM_DIGITS` for problems)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(plain(doc, digits), indent=indent, allow_nan=False)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write(text + "\n")
    os.chmod(tmp, 0o644)  # (mkstemp makes it private; results are for everyone to read)
    os.replace(tmp, path)


def read_json(path: Path) -> dict[str, Any]:
    with open(path, encoding="utf-8") as f:
        return json.load(f)


# ------------------------------------------------------------------------------ solvers
@dataclass(frozen=True)
class Solver:
    """One solver of a benchmark case.

    Attributes:
        name: key in the results (``usar-arm``, ``usar-arm batch``, ``mplib``...).
        kind: ``ours`` or ``peer``.
        command: the interpreter and script (and options); PROBLEMS and RESULTS are appended.
        skip: why it is not run (missing venv...), or "" when it runs.
        note: what is timed, in a few words (shown in the report).
        limit: run only the first ``limit`` problems of the set (a slow peer in the full
            run); ratios are then taken over the problems both solvers ran.
    """

    name: str
    kind: str
    command: tuple[str, ...]
    skip: str = ""
    note: str = ""
    limit: int | None = None


def ours(name: str, script: str, *options: str, note: str = "") -> Solver:
    """Our solver: ``bench/<script>`` run by this interpreter."""
    return Solver(name, "ours", (sys.executable, str(BENCH / script), *options), note=note)


def peer(peer_name: str, stage: str, note: str = "") -> Solver:
    """A peer's runner ``bench/peers/run_<peer>_<stage>.py`` in the peer's own venv (skipped,
    with the reason, when that venv is missing)."""
    script = PEERS_DIR / f"run_{peer_name}_{stage}.py"
    py = venvs.python_path(peer_name)
    skip = ""
    if not venvs.is_ready(peer_name):
        skip = venvs.missing_reason(peer_name)
    elif not script.is_file():
        skip = f"no runner {script.name}"
    return Solver(peer_name, "peer", (str(py), str(script)), skip, note)


@dataclass
class Outcome:
    """Merged results of one solver over all rounds."""

    solver: Solver
    results: list[dict[str, Any]] = field(default_factory=list)
    header: dict[str, Any] = field(default_factory=dict)
    process_seconds: list[float] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)


def chunks(problems: list[dict[str, Any]], rounds: int) -> list[list[dict[str, Any]]]:
    """``rounds`` interleaved chunks (problem i goes to chunk i mod rounds), none empty."""
    rounds = max(1, min(rounds, len(problems)))
    return [problems[r::rounds] for r in range(rounds)]


def run_alternating(spec: dict[str, Any], solvers: Sequence[Solver], workdir: Path,
                    rounds: int, label: str) -> dict[str, Outcome]:
    """Run every solver on the problems of ``spec`` in alternation (see the module docstring).

    A solver whose process fails or times out gets its chunk's problems marked failed with the
    reason; skipped solvers are not run. Returns solver name -> merged outcome.
    """
    workdir.mkdir(parents=True, exist_ok=True)
    active = [s for s in solvers if not s.skip]
    out = {s.name: Outcome(s) for s in solvers}
    for s in solvers:
        if s.skip:
            log(f"{label}: {s.name} skipped: {s.skip}")
    parts = chunks(spec["problems"], rounds)
    for r, whole in enumerate(parts):
        problem_file = workdir / f"{label}.round{r}.json"
        write_json(problem_file, {**spec, "problems": whole}, indent=None,
                   digits=PROBLEM_DIGITS)
        order = active[r % len(active):] + active[:r % len(active)] if active else []
        for s in order:
            part, source = whole, problem_file
            if s.limit is not None:
                allowed = {p["id"] for p in spec["problems"][:s.limit]}
                part = [p for p in whole if p["id"] in allowed]
                source = workdir / f"{label}.round{r}.first{s.limit}.json"
                write_json(source, {**spec, "problems": part}, indent=None,
                           digits=PROBLEM_DIGITS)
                if not part:
                    continue
            result_file = workdir / f"{label}.round{r}.{s.name.replace(' ', '_')}.json"
            result_file.unlink(missing_ok=True)
            begin = time.perf_counter()
            reason = _run(s, source, result_file)
            took = time.perf_counter() - begin
            o = out[s.name]
            o.process_seconds.append(took)
            if reason:
                o.errors.append(f"round {r}: {reason}")
                o.results += [{"id": p["id"], "success": False, "seconds": None,
                               "error": reason} for p in part]
                log(f"{label} round {r + 1}/{len(parts)}: {s.name} FAILED ({reason})")
                continue
            doc = read_json(result_file)
            o.results += doc.pop("results")
            o.header = doc
            ok = sum(1 for x in o.results[-len(part):] if x.get("success"))
            log(f"{label} round {r + 1}/{len(parts)}: {s.name} {ok}/{len(part)} answered "
                f"({took:.1f} s)")
    for o in out.values():
        o.results.sort(key=lambda x: x["id"])
    return out


LAUNCHED_AT = "BENCH_LAUNCHED_AT"
"""Environment variable: the wall-clock time (``time.time()``, s) at which the harness launched
the solver process (see :func:`since_launch`)."""


def since_launch() -> float:
    """Seconds since the harness launched this process (interpreter start and imports
    included): what a user waits for a command they type. A process not launched by the
    harness counts from the import of this module."""
    return time.time() - float(os.environ.get(LAUNCHED_AT, _IMPORTED))


_IMPORTED = time.time()


def _run(s: Solver, problems: Path, results: Path) -> str:
    """Run one solver process; "" on success, else why it failed."""
    env = {**os.environ, **ENVIRONMENT, LAUNCHED_AT: repr(time.time())}
    try:
        proc = subprocess.run([*s.command, str(problems), str(results)], capture_output=True,
                              text=True, timeout=RUNNER_TIMEOUT_S, env=env, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return f"timed out after {RUNNER_TIMEOUT_S:.0f} s"
    if proc.returncode != 0 or not results.is_file():
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
        return f"exit code {proc.returncode}: {' | '.join(tail)}"
    return ""


def by_id(results: list[dict[str, Any]]) -> dict[Any, dict[str, Any]]:
    return {r["id"]: r for r in results}


def solver_record(o: Outcome, raw: dict[str, list[Any]], summary: dict[str, Any]
                  ) -> dict[str, Any]:
    """The results-file entry of one solver: how it ran, raw per-problem figures, summary."""
    s = o.solver
    if s.skip:
        return {"kind": s.kind, "skipped": s.skip}
    header = {k: v for k, v in o.header.items() if k not in ("stage",)}
    return {"kind": s.kind, "note": s.note, "command": [Path(c).name for c in s.command],
            **header, "process_seconds": o.process_seconds, "errors": o.errors,
            "summary": summary, "raw": raw}


def base_summary(results: list[dict[str, Any]], verified: list[bool],
                 seconds_key: str = "seconds") -> dict[str, Any]:
    """Counts and time distribution: ``time_all_s`` over every attempted problem (a failure
    costs its time; errors without a time are left out), ``time_verified_s`` over verified
    successes only."""
    n = len(results)
    answered = sum(1 for r in results if r.get("success"))
    ok = sum(verified)
    secs = [r.get(seconds_key) for r in results]
    return {"problems": n, "answered": answered, "verified": ok,
            "success_rate": ok / n if n else None,
            "answered_rate": answered / n if n else None,
            "errors": sum(1 for r in results if "error" in r),
            "time_all_s": stats(secs),
            "time_verified_s": stats([t for t, v in zip(secs, verified, strict=True) if v])}


def stage_document(stage: str, mode: str, settings: dict[str, Any], cases: dict[str, Any],
                   targets: list[dict[str, Any]], started: float) -> dict[str, Any]:
    """The common top of every ``results/<stage>.json``."""
    return {"stage": stage, "mode": mode, "generated": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "wall_seconds": time.perf_counter() - started, "machine": machine(),
            "versions": versions(), "environment": ENVIRONMENT, "settings": settings,
            "targets": targets, "cases": cases}


def target(name: str, measured: float | None, threshold: float, better: str, unit: str,
           note: str = "") -> dict[str, Any]:
    """A pass/fail line: ``better`` is ``<=`` or ``>=``; a missing figure fails."""
    ok = measured is not None and (measured <= threshold if better == "<=" else
                                   measured >= threshold)
    return {"target": name, "measured": measured, "threshold": threshold, "better": better,
            "unit": unit, "pass": bool(ok), "note": note}


def timed_calls(fn: Callable[..., Any], *args: Any) -> tuple[Any, float]:
    """(fn(*args), wall seconds): the same clock as the peers' ``peerio.timed``."""
    return peerio.timed(fn, *args)


# ------------------------------------------------------------------------------ cases
Check = Callable[[dict[str, Any], dict[str, Any]], dict[str, Any]]


def build_case(problem_file: Path, spec: dict[str, Any], outcomes: dict[str, Outcome],
               check: Check, extra: Callable[[dict[str, list[Any]]], dict[str, Any]] | None = None,
               checks: dict[str, Check] | None = None) -> dict[str, Any]:
    """One case of a stage: every solver's raw per-problem figures (columns), its summary, and
    the time ratios usar-arm / peer measured in this run.

    ``check(problem, result)`` returns the per-problem row (must hold ``verified``);
    ``checks`` names solvers judged by a check of their own instead (a solver that claims more,
    e.g. collision-free IK answers); ``extra(columns)`` adds stage-specific summary figures.
    """
    problems = {p["id"]: p for p in spec["problems"]}
    solvers: dict[str, Any] = {}
    for name, o in outcomes.items():
        if o.solver.skip:
            solvers[name] = solver_record(o, {}, {})
            continue
        rows = []
        judge = (checks or {}).get(name, check)
        for r in o.results:
            row = {"id": r["id"], "answered": bool(r.get("success")),
                   "seconds": r.get("seconds"), **judge(problems[r["id"]], r)}
            if "error" in r:
                row["error"] = r["error"]
            rows.append(row)
        keys = sorted({k for row in rows for k in row}, key=lambda k: (k != "id", k))
        raw = {k: [row.get(k) for row in rows] for k in keys}
        summary = base_summary(o.results, raw.get("verified", []))
        if extra is not None:
            summary.update(extra(raw))
        solvers[name] = solver_record(o, raw, summary)
    return {"problems": {"file": str(problem_file), "sha256": sha256(problem_file),
                         "count": len(spec["problems"]), "generator": spec.get("generator")},
            "solvers": solvers, "ratios": ratios(solvers)}


def ratios(solvers: dict[str, Any]) -> dict[str, dict[str, dict[str, Any]]]:
    """peer -> our solver -> {median, mean, p90, problems}: our time / the peer's, over the
    problems both have a time for (every problem, unless a peer ran a subset or errored)."""
    out: dict[str, dict[str, dict[str, Any]]] = {}
    mine = {n: s for n, s in solvers.items() if s["kind"] == "ours" and s.get("raw")}
    for pname, p in solvers.items():
        if p["kind"] != "peer" or not p.get("raw"):
            continue
        theirs = {i: t for i, t in zip(p["raw"]["id"], p["raw"]["seconds"], strict=True)
                  if t is not None}
        out[pname] = {}
        for n, s in mine.items():
            pairs = [(t, theirs[i]) for i, t in zip(s["raw"]["id"], s["raw"]["seconds"],
                                                    strict=True)
                     if t is not None and i in theirs]
            a, b = stats([x for x, _ in pairs]), stats([y for _, y in pairs])
            out[pname][n] = {**{k: ratio(a[k], b[k]) for k in ("median", "mean", "p90")},
                             "problems": len(pairs)}
    return out


@dataclass(frozen=True)
class Context:
    """What a stage needs from the runner.

    Attributes:
        mode: ``quick`` or ``full``. out: the results folder. problems: set name -> file.
        work: scratch folder for the per-round files. rounds: alternation rounds.
        peers: the peers to run (None = all).
    """

    mode: str
    out: Path
    problems: dict[str, Path]
    work: Path
    rounds: int
    peers: frozenset[str] | None = None

    def problem(self, key: str) -> tuple[Path, dict[str, Any]]:
        path = self.problems[key]
        return path, read_json(path)

    def peer(self, name: str, stage: str, note: str = "", limit: int | None = None) -> Solver:
        """A peer solver, skipped with a reason when not selected; ``limit``: the first
        problems only (full mode)."""
        s = peer(name, stage, note)
        if self.peers is not None and name not in self.peers:
            return Solver(s.name, s.kind, s.command, "not selected (--peers)", note)
        return replace(s, limit=limit if self.mode == "full" else None)


def subset(outcomes: dict[str, Outcome], ids: set[Any]) -> dict[str, Outcome]:
    """The outcomes restricted to the problems ``ids`` (one scene of a multi-scene file)."""
    return {n: Outcome(o.solver, [r for r in o.results if r["id"] in ids], o.header,
                       o.process_seconds, o.errors) for n, o in outcomes.items()}
