"""The coverage-guided fuzz targets (``fuzz/``, atheris) run for a bounded time in CI.

Each target gets a fresh copy of its seed corpus and ``FUZZ_SECONDS`` of libFuzzer time; a
crash (any exception other than the typed error the target allows, or a failed invariant)
fails the test and the crashing input is kept in the test's folder. Longer runs by hand:
``python fuzz/fuzz_codec.py -max_total_time=3600 build/fuzz/codec fuzz/corpus/codec``.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import atheris  # noqa: F401  # the test extra installs it: missing is a failure, not a skip
import pytest

FUZZ = Path(__file__).resolve().parents[1] / "fuzz"
FUZZ_SECONDS = 10
TARGETS = ["codec", "scene", "limits", "trajectory"]


@pytest.mark.slow
@pytest.mark.parametrize("target", TARGETS)
def test_fuzz_target_finds_no_crash_in_bounded_time(target: str, tmp_path: Path) -> None:
    corpus = tmp_path / "corpus"
    shutil.copytree(FUZZ / "corpus" / target, corpus)
    proc = subprocess.run(
        [sys.executable, str(FUZZ / f"fuzz_{target}.py"), f"-max_total_time={FUZZ_SECONDS}",
         "-print_final_stats=1", f"-artifact_prefix={tmp_path}/", str(corpus)],
        capture_output=True, text=True, timeout=FUZZ_SECONDS + 120, cwd=tmp_path)
    crashes = sorted(p.name for p in tmp_path.glob("crash-*"))
    assert proc.returncode == 0 and not crashes, (crashes, proc.stderr[-4000:])
    runs = re.search(r"stat::number_of_executed_units:\s*(\d+)", proc.stderr)
    assert runs is not None and int(runs.group(1)) > 100, proc.stderr[-2000:]
    sys.stderr.write(f"fuzz_{target}: {runs.group(1)} inputs in {FUZZ_SECONDS} s\n")
