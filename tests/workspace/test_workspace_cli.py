"""``usar-arm reach``, ``place`` and ``batch`` as a user runs them: the files they write, the
exit codes of bad input, Ctrl-C and --resume, and Ray missing."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_INVALID_INPUT, EXIT_NO_IK, EXIT_OK, EXIT_UNAVAILABLE

REPO = Path(__file__).resolve().parents[2]
URDF = str(REPO / "robots" / "generated" / "KR60.urdf")
TARGETS = str(REPO / "examples" / "workspace" / "table-targets.yaml")
SMALL = ["--resolution", "0.3", "--orientations", "16"]


def _reach(out: Path, *extra: str) -> int:
    return main(["reach", "--urdf", URDF, *SMALL, "--out", str(out), "-q", *extra])


def test_reach_writes_the_map_its_record_and_three_slices(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    assert _reach(tmp_path, "--scene", "table", "--workers", "2", "--json") == EXIT_OK
    doc = json.loads(capsys.readouterr().out)
    with np.load(tmp_path / "reach.npz") as m:
        assert m["index"].dtype == np.float32 and m["index"].ndim == 3
        assert m["manipulability"].shape == m["index"].shape
        assert m["origin"].shape == (3,) and float(m["resolution"]) == 0.3
        assert str(m["frame"]) == "base_link"
        reached = int((m["index"] > 0).sum())
    assert doc["counts"]["voxels_reached"] == reached > 0
    assert doc["settings"]["orientations"] == 16 and doc["scene"]["name"] == "table"
    assert doc["run"]["workers"] == 2 and doc["run"]["units_per_second"] > 0
    assert set(doc["versions"]) >= {"usar-arm", "numpy", "python"}
    for name in ("reach-xz.png", "reach-xy.png", "reach-xy-shoulder.png"):
        assert imread(tmp_path / name).shape[0] > 400
    assert not (tmp_path / ".chunks").exists()
    assert json.loads((tmp_path / "reach.json").read_text())["counts"] == doc["counts"]


@pytest.mark.parametrize(("args", "says"), [
    (["--resolution", "0"], "--resolution"),
    (["--orientations", "0"], "--orientations"),
    (["--cone", "200"], "--cone"),
    (["--workers", "-1"], "--workers"),
    (["--resolution", "0.001"], "GiB"),
])
def test_reach_refuses_bad_settings_before_any_work(args: list[str], says: str, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["reach", "--urdf", URDF, *SMALL, *args, "--out", str(tmp_path / "m")])
    assert code == EXIT_INVALID_INPUT
    assert says in capsys.readouterr().err
    assert not (tmp_path / "m").exists()


def test_an_unanswering_ray_address_fails_within_its_timeout_before_any_planning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    begin = time.perf_counter()  # (planned, a 1 mm map would be refused as too large: 65)
    code = _reach(tmp_path / "m", "--ray", "127.0.0.1:1", "--ray-timeout", "1",
                  "--resolution", "0.001")
    assert code == EXIT_UNAVAILABLE and time.perf_counter() - begin < 10
    assert "127.0.0.1:1" in capsys.readouterr().err
    assert not (tmp_path / "m" / "reach.npz").exists()


def test_without_the_ray_extra_ray_says_how_to_install_it(tmp_path: Path) -> None:
    code = ("import sys; sys.modules['ray'] = None\n"
            "from usar_arm.cli.main import main\n"
            f"sys.exit(main(['reach', '--urdf', {URDF!r}, '--out', {str(tmp_path)!r}, "
            "'--ray', 'local']))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == EXIT_UNAVAILABLE, done.stderr
    assert "pip install 'usar-arm[ray]'" in done.stderr


def test_ctrl_c_keeps_the_finished_chunks_writes_nothing_else_and_resume_finishes(
        tmp_path: Path, ctrl_c_reaches_children: None) -> None:
    out = tmp_path / "map"

    # 0.08 m: about 100 chunks, some 4 s of work on two workers. At 0.12 m (32 chunks, 1.2 s
    # after the first one was kept) a test process starved by the workers and another test
    # sent its Ctrl-C after the job had ended (twice in fresh clones under make test).
    def command(folder: Path, *extra: str) -> list[str]:
        return [str(Path(sys.executable).parent / "usar-arm"), "reach", "--urdf", URDF,
                "--resolution", "0.08", "--orientations", "16", "--out", str(folder), "-q",
                *extra]

    argv = command(out, "--workers", "2")
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list((out / ".chunks").glob("chunk-*.npz")) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "--resume" in err
    kept = list((out / ".chunks").glob("chunk-*.npz"))
    assert kept and sorted(p.name for p in out.iterdir()) == [".chunks"]
    resumed = subprocess.run([*argv, "--resume", "--json"], capture_output=True, text=True,
                             timeout=300, check=False)
    assert resumed.returncode == EXIT_OK, resumed.stderr
    run = json.loads(resumed.stdout)["run"]
    assert run["chunks_resumed"] >= len(kept) and run["chunks_run"] > 0
    fresh = tmp_path / "fresh"
    again = subprocess.run(command(fresh, "--workers", "0"), capture_output=True, text=True,
                           timeout=300, check=False)
    assert again.returncode == EXIT_OK, again.stderr
    with np.load(out / "reach.npz") as a, np.load(fresh / "reach.npz") as b:
        assert np.array_equal(a["index"], b["index"])
        assert np.array_equal(a["best_q"], b["best_q"], equal_nan=True)


def test_place_ranks_bases_and_writes_the_best_with_its_solutions(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["place", "--urdf", URDF, "--targets", TARGETS, "--scene", "table",
                 "--step", "0.4", "--yaw-steps", "4", "--out", str(tmp_path), "--json", "-q"])
    assert code == EXIT_OK
    doc = json.loads(capsys.readouterr().out)
    best = doc["best"]
    assert doc["counts"]["feasible"] > 0 and best["score"] == doc["ranking"][0]["score"]
    scores = [r["score"] for r in doc["ranking"]]
    assert scores == sorted(scores, reverse=True)
    assert set(best["solutions"]) == {t["name"] for t in doc["targets"]}
    assert all(best["solutions"][t] for t in best["solutions"])
    assert imread(tmp_path / "placement.png").shape[0] > 400


def test_place_names_a_target_no_base_reaches(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    targets = tmp_path / "t.yaml"
    targets.write_text("targets:\n  - {name: near, xyz: [1.4, 0, 1.0], rpy: [3.14159, 0, 0]}\n"
                       "  - {name: sky, xyz: [1.4, 0, 9.0]}\n")
    code = main(["place", "--urdf", URDF, "--targets", str(targets), "--step", "0.5",
                 "--out", str(tmp_path / "o")])
    assert code == EXIT_NO_IK
    assert "'sky'" in capsys.readouterr().err


def test_place_reports_a_malformed_targets_file_with_its_line(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    targets = tmp_path / "t.yaml"
    targets.write_text("units: m-rad\ntargets:\n  - {name: a, xyz: [1, 2]}\n")
    code = main(["place", "--urdf", URDF, "--targets", str(targets), "--out", str(tmp_path)])
    assert code == EXIT_INVALID_INPUT
    err = capsys.readouterr().err
    assert "t.yaml:3" in err and "xyz" in err


PROBLEMS = REPO / "examples" / "workspace" / "problems.jsonl"


def _results(path: Path) -> list[dict]:
    """The result lines without what a clock measured (the time a problem took, which an IK
    failure's message also states)."""
    docs = [json.loads(line) for line in path.read_text().splitlines()]
    for d in docs:
        d.pop("seconds", None)
        if not d["ok"]:
            d["error"]["message"] = re.sub(r"after [0-9.]+ s", "after T s",
                                           d["error"]["message"])
    return docs


def test_batch_answers_in_input_order_with_typed_failures_whatever_the_workers(
        tmp_path: Path) -> None:
    problems = tmp_path / "p.jsonl"
    problems.write_text(PROBLEMS.read_text() + "".join(
        f'{{"id": "r{k}", "ik": {{"pose": [1.1, {0.1 * k - 0.5:.2f}, 1.1, 3.1, 0.2, 0]}}}}\n'
        for k in range(10)))
    for workers in ("0", "2"):
        assert main(["batch", str(problems), "--urdf", URDF, "--workers", workers,
                     "--out", str(tmp_path / workers), "-q"]) == EXIT_OK
    docs = _results(tmp_path / "0" / "results.jsonl")
    assert docs == _results(tmp_path / "2" / "results.jsonl")
    assert [d["line"] for d in docs] == [1, 2, 4, 5, 6, 7, 8, 9, 10, *range(11, 21)]
    by_id = {d["id"]: d for d in docs}
    assert by_id["a"]["ok"] and len(by_id["b"]["solutions"]) >= 1
    for plan in ("c", "c2"):  # planned by the default planner (the straight segment is blocked)
        assert by_id[plan]["ok"] and by_id[plan]["planner"] == "CompiledRRTConnect"
        assert len(by_id[plan]["waypoints"]) >= 3
    assert by_id["d"]["ok"] and by_id["d"]["motion"] == "lin"
    assert by_id["e"]["error"]["type"] == "UnreachableError"
    assert by_id["e"]["error"]["exit_code"] == EXIT_NO_IK
    assert by_id[None]["error"]["message"].startswith("not JSON")
    assert "6 joint values" in by_id["g"]["error"]["message"]
    assert "nosuch" in by_id["h"]["error"]["message"]
    summary = json.loads((tmp_path / "2" / "batch.json").read_text())
    assert summary["counts"]["results"] == len(docs)


def test_the_3d_view_serves_the_map(small_map: object) -> None:
    pytest.importorskip("viser", reason="the viz extra is not installed")
    import urllib.request

    from usar_arm.export.reach_view import serve_reach

    run = small_map
    m = run.map  # type: ignore[attr-defined]
    viewer = serve_reach(Path(URDF).read_text(), m.index, m.origin, m.resolution, port=0)
    try:
        with urllib.request.urlopen(viewer.url, timeout=10) as page:
            assert page.status == 200
    finally:
        viewer.stop()
