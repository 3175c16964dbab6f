"""``usar-arm tesseract-config`` end to end: the folder it writes is complete, its
``plan_example.py`` (quoted whole in its README) plans with every pipeline the folder defines
(OMPLPipeline, TrajOptPipeline, FreespacePipeline) in the Tesseract venv, and bad input is
refused with a clear message before anything is written."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.consumers.conftest import ROOT, tesseract_python
from usar_arm.urdf.tesseract_composer import PIPELINES

USAR_ARM = str(Path(sys.executable).parent / "usar-arm")
AS_LEARNT = ROOT / "robots" / "generated" / "as-learnt" / "KR60.urdf"
FILES = {"KR60.urdf", "KR60.srdf", "KR60.kinematics_plugins.yaml",
         "KR60.contact_managers_plugins.yaml", "task_composer_plugins.yaml", "package.xml",
         "plan_example.py", "README.md"}


def _cli(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([USAR_ARM, "tesseract-config", *args], capture_output=True, text=True,
                          timeout=300, check=False, env={**os.environ, **(env or {})})


def test_the_folder_is_complete_and_its_example_plans(tmp_path: Path) -> None:
    out = tmp_path / "kr60_tesseract"
    done = _cli("--urdf", str(AS_LEARNT), "--out", str(out), "--json")
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert doc["package"] == "kr60_tesseract" and doc["ik_solver"] == "KDLInvKinChainLMA"
    assert doc["reason"].startswith("KDL: OPW forward kinematics deviates")
    assert {Path(f).name for f in doc["files"]} == FILES == {p.name for p in out.iterdir()}
    srdf = (out / "KR60.srdf").read_text()
    assert '<kinematics_plugin_config filename="package://kr60_tesseract/KR60.kinematics_' \
           'plugins.yaml"/>' in srdf
    assert "contact_managers_plugin_config" in srdf
    script = (out / "plan_example.py").read_text()
    assert script.rstrip() in (out / "README.md").read_text()
    for pipeline in PIPELINES:
        run = subprocess.run([str(tesseract_python()), str(out / "plan_example.py"), pipeline],
                             cwd=tmp_path, capture_output=True, text=True, timeout=300,
                             check=False)
        assert run.returncode == 0, f"{pipeline}: {run.stderr[-3000:]}"
        rows = re.findall(r"t = +([0-9.]+) s +q = \[([^\]]+)\]", run.stdout)
        assert len(rows) >= 2, f"{pipeline}: {run.stdout[-2000:]}"
        first = [float(x) for x in rows[0][1].split()]
        last = [float(x) for x in rows[-1][1].split()]
        assert first == pytest.approx([0.0] * 6) and last == pytest.approx([0.5] + [0.0] * 5)
        times = [float(t) for t, _ in rows]
        assert times == sorted(times) and times[-1] > 0.0, f"{pipeline}: {times}"


def test_the_docs_show_only_pipelines_the_folder_defines() -> None:
    page = ROOT / "docs" / "moveit-tesseract.md"
    shown = re.findall(r"plan_example\.py (\w+)", page.read_text())
    assert shown and set(shown) <= set(PIPELINES), shown


def _tree(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir()}


def test_discovering_the_robot_writes_the_same_folder(tmp_path: Path) -> None:
    """The as-learnt KR60 discovered (--no-calibrate; a fresh description cache) gives, byte
    for byte, the folder its checked-in description gives (tests/cli checks the calibrated
    default the same way)."""
    found, given = tmp_path / "a" / "kr60_t", tmp_path / "b" / "kr60_t"
    done = _cli("--robot", "KR60", "--no-calibrate", "--out", str(found), "-q",
                env={"USAR_ARM_CACHE": str(tmp_path / "cache")})
    assert done.returncode == 0, done.stderr
    assert "wrote Tesseract config kr60_t (8 files, inverse kinematics KDLInvKinChainLMA; " \
           "description as learnt)" in done.stdout
    assert _cli("--urdf", str(AS_LEARNT), "--out", str(given), "-q").returncode == 0
    assert set(_tree(found)) == FILES
    assert _tree(found) == _tree(given)


def test_bad_input_is_refused_and_nothing_is_written(tmp_path: Path) -> None:
    bad = tmp_path / "no room"
    done = _cli("--urdf", str(AS_LEARNT), "--out", str(bad))
    assert done.returncode == 65 and "cannot be a ROS package name" in done.stderr
    assert not bad.exists()
    lonely = tmp_path / "in" / "KR60.urdf"
    lonely.parent.mkdir()
    lonely.write_text(AS_LEARNT.read_text())
    done = _cli("--urdf", str(lonely), "--out", str(tmp_path / "out"))
    assert done.returncode == 65 and "no SRDF beside the URDF" in done.stderr
    assert not (tmp_path / "out").exists()
