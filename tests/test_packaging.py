"""Installing usar-arm prints nothing but pip's own progress: the build backend (setuptools, at
the version pyproject.toml asks for) has no warning about the project's metadata (issue 39: the
license as a TOML table was deprecated, and every install printed that twice)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_building_the_metadata_warns_about_nothing(tmp_path: Path) -> None:
    # The metadata alone, built as pip builds it (an isolated build environment with the
    # build-system's requirements): the project's files that it reads, no package code.
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, tmp_path / name)
    (tmp_path / "usar_arm").mkdir()
    (tmp_path / "usar_arm" / "__init__.py").write_text("")
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--dry-run", "--no-deps",
                           "--ignore-installed", "--no-color", str(tmp_path)],
                          capture_output=True, text=True, timeout=300, check=False)
    output = done.stdout + done.stderr
    assert done.returncode == 0, output[-3000:]
    assert "Would install usar-arm" in output, output[-3000:]
    warned = [line.strip() for line in output.splitlines()
              if "Warning" in line and "Location 'file:" not in line]  # (pip.conf's own)
    assert warned == [], "the build backend warned:\n" + "\n".join(warned)
