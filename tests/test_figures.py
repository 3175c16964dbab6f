"""The prose's figures come from bench/results (tools/figures.py): each marked figure is what the
committed results give, so the README and the docs cannot drift from the measurement."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import figures  # noqa: E402


def test_every_marked_figure_is_what_the_committed_results_give() -> None:
    stale = [f"{f.path.relative_to(ROOT)}:{f.line}: {f.written!r}, results give "
             f"{f.expected!r} ({f.spec})"
             for f in figures.figures(figures.documents()) if f.written != f.expected]
    assert stale == [], "run python tools/figures.py --write after a benchmark run:\n" + \
        "\n".join(stale)


@pytest.fixture
def results(tmp_path: Path) -> Path:
    doc = {"cases": {"udk wire, no correction": {"max_m": 0.0021874, "runs": [3, 1, 2]},
                     "calibrated": {"max_m": 0.0000808, "runs": [5]}}}
    (tmp_path / "execution.json").write_text(json.dumps(doc))
    return tmp_path


@pytest.mark.parametrize(("spec", "text"), [
    ("execution.json#/cases/udk wire, no correction/max_m | *1e3 | .2f", "2.19"),
    ("execution.json#/cases/*/max_m | max | *1000 | .3g", "2.19"),
    ("execution.json#/cases/*/max_m | min | *1e3 | .3f", "0.081"),
    ("execution.json#/cases/udk wire, no correction/runs | max", "3"),
    ("execution.json#/cases/udk wire, no correction/runs/1", "1"),
    ("execution.json#/cases/* | len", "2"),
    ("execution.json#/cases/calibrated/max_m | /#/cases/udk wire, no correction/max_m | .4f",
     "0.0369"),
    ("execution.json#/cases/calibrated/max_m | inv | .0f", "12376"),
])
def test_a_spec_reads_a_pointer_and_applies_its_steps(results: Path, spec: str,
                                                       text: str) -> None:
    assert figures.evaluate(spec, results) == text


def test_a_stale_figure_is_found_and_rewritten(results: Path, tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("as learnt <!-- fig execution.json#/cases/udk wire, no correction/max_m "
                    "| *1e3 | .1f -->about 1<!-- /fig --> mm\n")
    (found,) = figures.figures([page], results)
    assert (found.line, found.written, found.expected) == (1, "about 1", "2.2")
    assert figures.rewrite(page, results) == 1
    assert "-->2.2<!-- /fig --> mm" in page.read_text()
    (again,) = figures.figures([page], results)
    assert again.written == again.expected


def test_a_pointer_to_nothing_is_reported_with_the_keys_there(results: Path) -> None:
    with pytest.raises(KeyError, match=r"no 'nope'.*udk wire, no correction"):
        figures.evaluate("execution.json#/cases/nope/max_m", results)


def test_the_performance_page_includes_the_summary_the_results_give() -> None:
    """docs/performance.md shows bench/results/summary.md as it is (mkdocs' snippets), and that
    file is what bench/report_summary.py writes from the committed results, so the published
    table cannot be edited by hand or drift from the run."""
    sys.path.insert(0, str(ROOT / "bench"))
    import report
    from report_summary import summary_lines

    results = ROOT / "bench" / "results"
    docs = {s: json.loads((results / f"{s}.json").read_text()) for s in report.SECTIONS
            if (results / f"{s}.json").is_file()}
    run = json.loads((results / "run.json").read_text())
    expected = "\n".join(summary_lines(docs, run)) + "\n"
    assert (results / "summary.md").read_text() == expected, \
        "bench/results/summary.md differs: run python bench/report.py bench/results"
    assert '--8<-- "bench/results/summary.md"' in (ROOT / "docs" / "performance.md").read_text()
