"""The commands name shipped worlds and scenes by the one rule of usar_arm.core.named_file, in a
working folder that holds folders and files of the same names (issue 39: after ``usar-arm urdf
--out-dir default``, ``usar-arm sim`` there failed with "no world file default (shipped worlds:
default, rooms)"; a folder named ``table`` broke ``--scene table``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
KR60 = ROOT / "robots" / "generated" / "KR60.urdf"
POSE = ["--pose", "1.45", "-0.45", "1.1", "0", "3.14159", "0"]


def usar_arm(*argv: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "usar_arm", *argv], capture_output=True,
                          text=True, timeout=300, check=False, cwd=cwd)


def test_a_folder_named_like_a_shipped_world_or_scene_does_not_hide_it(tmp_path: Path) -> None:
    (tmp_path / "default").mkdir()  # as `usar-arm urdf --out-dir default` leaves it
    (tmp_path / "table").mkdir()
    drawn = usar_arm("render", "--world", "default", "--out", "w.png", cwd=tmp_path)
    assert drawn.returncode == 0, drawn.stderr[-2000:]
    assert (tmp_path / "w.png").stat().st_size > 1000 and "Warning" not in drawn.stderr
    solved = usar_arm("ik", "--urdf", str(KR60), "--scene", "table", *POSE, cwd=tmp_path)
    assert solved.returncode == 0, solved.stderr[-2000:]


def test_naming_the_folder_as_a_path_says_it_is_a_folder(tmp_path: Path) -> None:
    (tmp_path / "table").mkdir()
    done = usar_arm("ik", "--urdf", str(KR60), "--scene", "./table", *POSE, cwd=tmp_path)
    assert done.returncode == 65
    assert "./table: is a folder, not a scene file (a name without a folder or suffix names " \
           "a shipped scene: empty, table, shelf, cage)" in done.stderr
