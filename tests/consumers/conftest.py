"""Fixtures of the consumer tests: the descriptions Tesseract is given, the Tesseract venv and
the driver that runs in it (``tesseract_driver.py``, which imports nothing from usar-arm)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import pytest

from usar_arm.robot import Robot, robot_from_files
from usar_arm.urdf.tesseract import TesseractConfig, tesseract_config

ROOT = Path(__file__).resolve().parents[2]
DRIVER = Path(__file__).with_name("tesseract_driver.py")
TESSERACT_PYTHON = ROOT / "bench" / ".venvs" / "tesseract" / "bin" / "python"
SCENES = ("empty", "table", "shelf", "cage")
SPHERICAL_WRIST = "KR60-spherical-wrist"
"""The as-learnt KR60 with joint 6's axis moved 2 mm onto joint 4's: an exact OPW arm, for the
OPW solver (the USARSim KR60's wrist axes miss each other by 2 mm, so it gets KDL)."""


def tesseract_python() -> Path:
    """The Tesseract venv's python; fails (never skips) when it is missing."""
    if not TESSERACT_PYTHON.is_file():
        pytest.fail(f"no Tesseract venv at {TESSERACT_PYTHON.parent.parent}: `make test` "
                    "creates it, or `python3 bench/peers/venvs.py --only tesseract`")
    return TESSERACT_PYTHON


def run_driver(request: dict[str, Any], work: Path, timeout: float = 600) -> dict[str, Any]:
    """Run the driver in the Tesseract venv on ``request``; its answer."""
    work.mkdir(parents=True, exist_ok=True)
    req, out = work / "request.json", work / "answer.json"
    req.write_text(json.dumps(request))
    done = subprocess.run([str(tesseract_python()), str(DRIVER), str(req), str(out)],
                          capture_output=True, text=True, timeout=timeout, check=False)
    assert done.returncode == 0, f"driver failed ({done.returncode}):\n{done.stderr[-4000:]}"
    return dict(json.loads(out.read_text()))


def _spherical_wrist(folder: Path) -> tuple[Path, Path]:
    source = ROOT / "robots" / "generated" / "as-learnt"
    urdf = (source / "KR60.urdf").read_text()
    moved = urdf.replace('<origin xyz="0.152 0.07 0" rpy="0 0 0"/>',
                         '<origin xyz="0.152 0.068 0" rpy="0 0 0"/>')
    assert moved != urdf, "the as-learnt KR60's joint_a6 origin changed: update this fixture"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "KR60.urdf").write_text(moved)
    (folder / "KR60.srdf").write_text((source / "KR60.srdf").read_text())
    return folder / "KR60.urdf", folder / "KR60.srdf"


@pytest.fixture(scope="session")
def descriptions(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, Path]]:
    """name -> (URDF, SRDF): the checked-in KR60 (calibrated, as learnt), the Fanuc on its
    rail (described by ``usar-arm urdf`` from the embedded simulator) and the spherical-wrist
    KR60."""
    generated = ROOT / "robots" / "generated"
    fanuc = tmp_path_factory.mktemp("fanuc")
    done = subprocess.run([str(Path(__import__("sys").executable).parent / "usar-arm"), "urdf",
                           "--robot", "Fanuc_M16iB20", "--no-calibrate", "--out-dir",
                           str(fanuc), "-q"], capture_output=True, text=True, timeout=300,
                          check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    return {"KR60": (generated / "KR60.urdf", generated / "KR60.srdf"),
            "KR60-as-learnt": (generated / "as-learnt" / "KR60.urdf",
                               generated / "as-learnt" / "KR60.srdf"),
            "Fanuc_M16iB20": (fanuc / "Fanuc_M16iB20.urdf", fanuc / "Fanuc_M16iB20.srdf"),
            SPHERICAL_WRIST: _spherical_wrist(tmp_path_factory.mktemp("spherical") / "in")}


def configure(urdf: Path, srdf: Path, out: Path) -> tuple[Robot, TesseractConfig]:
    """usar-arm's Robot of a description and its Tesseract config, written into ``out``."""
    robot = robot_from_files(urdf, srdf)
    config = tesseract_config(robot.chain, robot.urdf, srdf.read_text(), out.name,
                              robot.states.get("home"))
    out.mkdir(parents=True, exist_ok=True)
    for name, text in config.files.items():
        (out / name).write_text(text)
    return robot, config
