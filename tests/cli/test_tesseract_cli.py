"""``usar-arm tesseract-config``'s checks of its input, before any work: where it may write
(a folder, never into or under a file, never into a folder usar-arm did not write), the
folder's name (a ROS package name, REP-144), and --srdf only with --urdf. Writing again into a
folder replaces its files and keeps, and lists, any other file. A discovered arm is written as
``usar-arm urdf`` writes it by default, calibrated through its tip sensor (the calibration the
description cache holds, else a tour), and so is moveit-config's; --no-calibrate: as learnt."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from usar_arm.arm.tour_calibration import CalibrationSettings
from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_INVALID_INPUT, EXIT_OK, EXIT_USAGE
from usar_arm.description.cache import cache_folder, calibrated_folder, store_calibrated
from usar_arm.description.embedded import run_discovery
from usar_arm.description.pipeline import DescribeOptions
from usar_arm.urdf.tesseract_package import package_problem, suggest_package_name

GENERATED = Path(__file__).resolve().parents[2] / "robots" / "generated"
KR60 = str(GENERATED / "as-learnt" / "KR60.urdf")
FANUC = str(GENERATED / "as-learnt" / "Fanuc_M16iB20.urdf")


def _tree(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("out", ["a_file", "a_file/kr60_tesseract"])
def test_a_file_in_the_way_is_refused_and_nothing_is_written(
        out: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "a_file").write_text("mine\n")
    code = main(["tesseract-config", "--urdf", KR60, "--out", str(tmp_path / out)])
    assert code == EXIT_INVALID_INPUT
    assert f"{tmp_path / 'a_file'} is a file" in capsys.readouterr().err
    assert _tree(tmp_path) == {"a_file": b"mine\n"}


@pytest.mark.parametrize(("name", "rule"), [
    ("KR60_tesseract", "lowercase"), ("kr60-tesseract", "'-'"), ("no room", "' '"),
    ("60kr", "start with a letter"), ("kr60__t", "two in a row"), ("kr60_", "at the end"),
    ("k", "two characters"), ("kr60.tesseract", "'.'")])
def test_a_folder_name_ros_would_refuse_is_refused_with_a_valid_name(
        name: str, rule: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["tesseract-config", "--urdf", KR60, "--out", str(tmp_path / name)])
    message = capsys.readouterr().err
    assert code == EXIT_INVALID_INPUT and "cannot be a ROS package name" in message
    assert rule in message and "REP-144" in message
    suggested = message.rsplit("Use e.g. '", 1)[1].split("'")[0]
    assert package_problem(suggested) is None, suggested
    assert not (tmp_path / name).exists()


def test_suggested_names_keep_what_they_can() -> None:
    assert suggest_package_name("KR60-Tesseract") == "kr60_tesseract"
    assert suggest_package_name("no room") == "no_room"
    assert suggest_package_name("9", "Fanuc_M16iB20") == "fanuc_m16ib20_tesseract"
    for good in ("kr60_tesseract", "cell2", "ab"):
        assert package_problem(good) is None


def test_srdf_without_urdf_is_a_usage_error(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["tesseract-config", "--srdf", KR60.replace(".urdf", ".srdf"), "--out",
              str(tmp_path / "kr60_tesseract")])
    assert exit_.value.code == EXIT_USAGE
    assert "--srdf goes with --urdf" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_a_folder_usar_arm_did_not_write_is_refused(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "my_package"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine\n")
    code = main(["tesseract-config", "--urdf", KR60, "--out", str(folder)])
    assert code == EXIT_INVALID_INPUT
    assert "already holds notes.txt and is not a package usar-arm wrote" in \
        capsys.readouterr().err
    assert _tree(folder) == {"notes.txt": b"mine\n"}


def test_writing_again_replaces_its_files_and_keeps_and_lists_the_others(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "cell_tesseract"
    assert main(["tesseract-config", "--urdf", FANUC, "--out", str(folder), "-q"]) == EXIT_OK
    fanuc = _tree(folder)
    (folder / "my_notes.txt").write_text("mine\n")
    capsys.readouterr()
    assert main(["tesseract-config", "--urdf", KR60, "--out", str(folder), "--json"]) == EXIT_OK
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    kr60 = _tree(folder)
    written = {Path(p).name for p in doc["files"]}
    stale = sorted(n for n in fanuc if n.startswith("Fanuc_M16iB20."))
    assert doc["other_files"] == sorted([*stale, "my_notes.txt"])
    assert set(kr60) == written | set(doc["other_files"])
    for name in stale:  # kept as they were: usar-arm deletes nothing
        assert kr60[name] == fanuc[name]
    for shared in ("README.md", "package.xml", "plan_example.py"):
        assert kr60[shared] != fanuc[shared] and b"KR60" in kr60[shared]
    assert "did not write, kept as they were: Fanuc_M16iB20." in captured.err
    leftovers = [p.name for p in folder.iterdir() if p.name.startswith(".")]
    assert leftovers == []  # no temporary file left behind


# ---------------------------------------------------------------- which description is written
def _seed_calibrated(cache: Path, robot: str) -> None:
    """Put the checked-in calibrated description of ``robot`` in the description cache, where
    a default calibration of the arm would have put it."""
    options = DescribeOptions(robot=robot)
    settings = CalibrationSettings()
    folder = calibrated_folder(cache_folder(run_discovery(options), options, cache),
                               settings.key())
    files = {f"{robot}.{suffix}": (GENERATED / f"{robot}.{suffix}").read_text()
             for suffix in ("urdf", "srdf", "joint_limits.yaml", "discovery.json",
                            "readings.csv")}
    store_calibrated(folder, files, f"{robot}.urdf", "2026-11-25T00:00:00+00:00", 321,
                     settings.key())


def test_a_discovered_arm_is_written_calibrated_from_the_cache_as_urdf_writes_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))
    _seed_calibrated(tmp_path / "cache", "KR60")
    found, given = tmp_path / "a" / "kr60_tesseract", tmp_path / "b" / "kr60_tesseract"
    assert main(["tesseract-config", "--robot", "KR60", "--out", str(found), "--json"]) == EXIT_OK
    captured = capsys.readouterr()
    assert json.loads(captured.out)["description"].startswith("calibrated")
    assert "calibrated description from the cache" in captured.err
    assert "poses" not in captured.err
    assert main(["tesseract-config", "--urdf", str(GENERATED / "KR60.urdf"), "--out",
                 str(given), "-q"]) == EXIT_OK
    assert _tree(found) == _tree(given)
    package = tmp_path / "kr60_moveit_config"
    assert main(["moveit-config", "--robot", "KR60", "--out", str(package), "-q"]) == EXIT_OK
    assert (package / "config" / "KR60.urdf").read_bytes() == \
        (GENERATED / "KR60.urdf").read_bytes()


def test_no_calibrate_writes_the_arm_as_learnt(tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))
    _seed_calibrated(tmp_path / "cache", "KR60")
    out = tmp_path / "kr60_tesseract"
    assert main(["tesseract-config", "--robot", "KR60", "--no-calibrate", "--out", str(out),
                 "-q"]) == EXIT_OK
    assert (out / "KR60.urdf").read_bytes() == (GENERATED / "as-learnt" / "KR60.urdf").read_bytes()
    package = tmp_path / "kr60_moveit_config"
    assert main(["moveit-config", "--robot", "KR60", "--no-calibrate", "--out", str(package),
                 "-q"]) == EXIT_OK
    assert (package / "config" / "KR60.urdf").read_bytes() == \
        (GENERATED / "as-learnt" / "KR60.urdf").read_bytes()


def test_no_calibrate_with_urdf_is_a_usage_error(tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["tesseract-config", "--urdf", KR60, "--no-calibrate", "--out",
              str(tmp_path / "kr60_tesseract")])
    assert exit_.value.code == EXIT_USAGE
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_without_a_cached_calibration_the_arm_is_toured_once(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """A tour (about 35 s) calibrates the KR60, and the next config command takes that
    calibration from the cache instead of touring again."""
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "kr60_tesseract"
    assert main(["tesseract-config", "--robot", "KR60", "--out", str(out), "-q"]) == EXIT_OK
    assert "a tour through 14 poses" in capsys.readouterr().err
    package = tmp_path / "kr60_moveit_config"
    assert main(["moveit-config", "--robot", "KR60", "--out", str(package), "--json"]) == EXIT_OK
    captured = capsys.readouterr()
    assert "poses" not in captured.err and json.loads(captured.out)["calibrated"] is True
    toured = (out / "KR60.urdf").read_bytes()
    assert (package / "config" / "KR60.urdf").read_bytes() == toured
    assert toured != (GENERATED / "as-learnt" / "KR60.urdf").read_bytes()
