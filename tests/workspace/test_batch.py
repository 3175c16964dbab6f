"""Batch jobs: chunks sized from each kind's measured cost, and a key that covers every
problem's content, so that --resume never hands back another file's answers."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_INVALID_INPUT, EXIT_OK
from usar_arm.core.job_errors import ResumeMismatchError
from usar_arm.planning.robot import Robot
from usar_arm.workspace import batch_job as batch
from usar_arm.workspace.batch_file import parse_problems
from usar_arm.workspace.jobs import CHUNKS, backend_for

REPO = Path(__file__).resolve().parents[2]
URDF = str(REPO / "robots" / "generated" / "KR60.urdf")


def _ik_lines(n: int, x: float = 1.1) -> str:
    return "".join(f'{{"id": {k}, "ik": {{"pose": [{x}, {0.01 * (k % 90) - 0.45:.2f}, 1.1, '
                   f'3.1, 0.2, 0]}}}}\n' for k in range(n))


def _plan_line(k: int) -> str:
    return (f'{{"id": "p{k}", "plan": {{"start": [0, -1.2, 1.2, 0, 0.5, 0], '
            f'"goal": [0.{k % 9}, -1.1, 1.1, 0, 0.4, 0]}}}}\n')


def test_an_ik_only_file_is_cut_into_chunks_of_at_least_the_computed_size() -> None:
    problems, _ = parse_problems(_ik_lines(6001))
    chunks = batch.chunk_problems(problems)
    least = math.ceil(batch.CHUNK_US / batch.COST_US["ik"])
    assert least * batch.COST_US["ik"] >= 50_000  # the floor: 50 ms of typical work
    assert all(len(c) >= least for c in chunks[:-1]) and len(chunks) == math.ceil(6001 / least)
    assert [p.line for c in chunks for p in c] == list(range(1, 6002))  # input order, all


def test_every_chunk_but_the_last_holds_at_least_50_ms_of_typical_work() -> None:
    text = "".join(_plan_line(k) if k % 7 == 0 else _ik_lines(1) for k in range(3000))
    problems, _ = parse_problems(text)
    chunks = batch.chunk_problems(problems)
    costs = [sum(batch.COST_US[p.kind] for p in c) for c in chunks]
    assert len(chunks) > 2 and min(costs[:-1]) >= max(50_000, batch.CHUNK_US)
    assert sum(len(c) for c in chunks) == 3000


def _job_key(text: str, seed: int = 0) -> str:
    problems, _ = parse_problems(text)
    job = batch.batch_job(problems, lambda: None, {}, batch.BatchOptions(seed=seed),  # type: ignore[arg-type, return-value]
                          "urdf", "0")
    return job.key


def test_the_key_covers_each_problems_content_not_only_its_line_and_kind() -> None:
    one = _ik_lines(5)
    assert _job_key(one) == _job_key(one)
    assert _job_key(one) != _job_key(_ik_lines(5, x=1.2))  # the same lines and kinds
    assert _job_key(one) != _job_key(one.replace('"id": 3', '"id": "three"'))
    assert _job_key(one) != _job_key(one, seed=1)


def test_resuming_with_a_changed_file_is_refused_naming_what_differs(
        kr60: Robot, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A run of p1 interrupted after its chunks were kept; the same command on p2 (other poses,
    the same lines and kinds) with --resume must not return p1's answers."""
    p1, p2 = tmp_path / "p1.jsonl", tmp_path / "p2.jsonl"
    p1.write_text(_ik_lines(6))
    p2.write_text(_ik_lines(6, x=1.25))
    out = tmp_path / "out"
    problems, bad = parse_problems(p1.read_text())
    batch.run_batch(kr60, problems, bad, batch.BatchOptions(), backend_for(0), out)
    assert list((out / CHUNKS).glob("chunk-*.npz"))  # (kept until the outputs are written)

    code = main(["batch", str(p2), "--urdf", URDF, "--workers", "0", "--out", str(out),
                 "--resume", "-q"])
    assert code == EXIT_INVALID_INPUT
    err = capsys.readouterr().err
    assert "problems differ" in err and "--resume" in err
    assert not (out / "results.jsonl").exists()

    problems2, bad2 = parse_problems(p2.read_text())
    with pytest.raises(ResumeMismatchError) as refused:
        batch.run_batch(kr60, problems2, bad2, batch.BatchOptions(), backend_for(0), out,
                        resume=True)
    assert refused.value.differences == ("problems",)

    code = main(["batch", str(p1), "--urdf", URDF, "--workers", "0", "--out", str(out),
                 "--resume", "--json", "-q"])
    assert code == EXIT_OK
    run = json.loads(capsys.readouterr().out)["run"]
    assert run["chunks_resumed"] == 1 and run["chunks_run"] == 0
    fresh = tmp_path / "fresh"
    assert main(["batch", str(p1), "--urdf", URDF, "--workers", "0", "--out", str(fresh),
                 "-q"]) == EXIT_OK
    assert _answers(out) == _answers(fresh)


def _answers(folder: Path) -> list[dict]:
    docs = [json.loads(line) for line in (folder / "results.jsonl").read_text().splitlines()]
    for d in docs:
        d.pop("seconds")
    return docs
