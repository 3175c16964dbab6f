"""The numbered examples run as a user runs them, so they never rot."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("[0-9]*.py"))
EXPECTED = {"01": "wrote", "02": "solutions", "03": "blended", "04": "back home, settled: True",
            "05": "part placed in the bin: yes", "06": "held out", "07": "best base",
            "08": "cycle done through ROS 2", "09": "planned around the post",
            "10": "vacuum pick and place done through ROS 2"}


def test_every_example_has_an_expected_output() -> None:
    """Each numbered example is run by the slow test below, which checks its output."""
    assert sorted(p.name[:2] for p in EXAMPLES) == sorted(EXPECTED)


@pytest.mark.slow
@pytest.mark.parametrize("example", EXAMPLES, ids=[e.stem for e in EXAMPLES])
def test_an_example_runs_and_prints_what_it_promises(example: Path, tmp_path: Path) -> None:
    run = subprocess.run([sys.executable, str(example)], capture_output=True, text=True,
                         timeout=300, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    assert EXPECTED[example.name[:2]] in run.stdout
    assert "Traceback" not in run.stderr
