"""The description cache keys a calibrated description by the arm's CONF/GEO lines (the entry)
and by the calibration's settings (the sub-folder), so a second `usar-arm urdf` of the same arm
with the same settings writes the cached calibration without touring."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from usar_arm.arm.facade import Arm
from usar_arm.arm.tour_calibration import CalibrationSettings, cached_calibration
from usar_arm.calibrate.bounds import Bounds
from usar_arm.calibrate.identification import CalibrationOptions
from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_OK
from usar_arm.description.cache import (
    cache_folder,
    calibrated_folder,
    latest_calibrated,
    store_calibrated,
)
from usar_arm.description.embedded import run_discovery
from usar_arm.description.pipeline import DescribeOptions

ROOT = Path(__file__).resolve().parents[2]
GOLDEN = ROOT / "robots" / "generated"
NAMES = ("KR60.urdf", "KR60.srdf", "KR60.joint_limits.yaml", "KR60.discovery.json",
         "KR60.readings.csv")


def _store(entry: Path, settings: CalibrationSettings, made: str, urdf: str | None = None
           ) -> Path:
    files = {n: (GOLDEN / n).read_text() for n in NAMES}
    if urdf is not None:
        files["KR60.urdf"] = urdf
    folder = calibrated_folder(entry, settings.key())
    store_calibrated(folder, files, "KR60.urdf", made, 321, settings.key())
    return folder


def test_the_key_changes_with_every_setting_and_only_then(tmp_path: Path) -> None:
    scene_a, scene_b = tmp_path / "a" / "s.yaml", tmp_path / "b" / "s.yaml"
    for path, text in ((scene_a, "obstacles: []\n"), (scene_b, "obstacles: [{}]\n")):
        path.parent.mkdir()
        path.write_text(text)
    base = CalibrationSettings()
    same = CalibrationSettings(14, None, 0, CalibrationOptions())
    others = [CalibrationSettings(poses=18), CalibrationSettings(seed=1),
              CalibrationSettings(scene="table"), CalibrationSettings(scene=str(scene_a)),
              CalibrationSettings(scene=str(scene_b)),
              CalibrationSettings(options=CalibrationOptions(quantisation="midpoint")),
              CalibrationSettings(options=CalibrationOptions(bounds=Bounds(joint_m=0.03)))]
    entry = tmp_path / "entry"
    folders = [calibrated_folder(entry, s.key()) for s in [base, *others]]
    assert calibrated_folder(entry, same.key()) == folders[0]
    assert len(set(folders)) == len(folders)  # the same-named scene files differ by content
    assert all(f.parent == entry for f in folders)


def test_a_description_made_by_an_older_generator_is_not_taken_from_the_cache(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The entry's key covers the generator's version: a description cached by a generator
    that wrote other files is made again, not served."""
    import usar_arm.description.cache as robot_module

    options = DescribeOptions(robot="KR60")
    record = run_discovery(options)
    now = robot_module.description_key(record, options)
    monkeypatch.setattr(robot_module, "GENERATOR", robot_module.GENERATOR + 1)
    assert robot_module.description_key(record, options) != now


def test_a_stored_calibration_is_found_by_its_settings_and_arm_connect_takes_the_latest(
        tmp_path: Path) -> None:
    entry = tmp_path / "entry"
    _store(entry, CalibrationSettings(), "2024-01-01T00:00:00+00:00")
    later = _store(entry, CalibrationSettings(poses=18), "2024-02-01T00:00:00+00:00",
                   urdf=(GOLDEN / "KR60.urdf").read_text().replace("<robot", "<robot ", 1))
    hit = cached_calibration(entry, "KR60", CalibrationSettings())
    assert hit is not None and hit.readings == 321 and hit.made.startswith("2024-01-01")
    assert hit.files["KR60.urdf"] == (GOLDEN / "KR60.urdf").read_text()
    assert set(hit.files) == set(NAMES)
    assert cached_calibration(entry, "KR60", CalibrationSettings(poses=10)) is None
    assert latest_calibrated(entry, "KR60") == later
    (later / "made.json").unlink()  # a broken entry is ignored, not fatal
    assert latest_calibrated(entry, "KR60") != later


def test_the_second_urdf_takes_the_cached_calibration_without_touring(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """The cache entry of this server's KR60 holds a calibration with the default settings
    (the checked-in one, put there by the test): `usar-arm urdf` writes it, says where it came
    from, and never tours (the tour is replaced by a failure)."""
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))

    def no_tour(*args: object, **kwargs: object) -> None:
        raise AssertionError("toured although the cache holds the calibration")

    monkeypatch.setattr("usar_arm.arm.tour_calibration.collect", no_tour)
    options = DescribeOptions()
    entry = cache_folder(run_discovery(options), options)
    _store(entry, CalibrationSettings(), "2024-01-01T00:00:00+00:00")
    out = tmp_path / "out"
    begin = time.perf_counter()
    assert main(["urdf", "--robot", "KR60", "--out-dir", str(out)]) == EXIT_OK
    seconds = time.perf_counter() - begin
    text = capsys.readouterr().out
    assert ("calibrated description from the cache, made 2024-01-01T00:00:00+00:00 from 321 "
            "readings; --recalibrate to tour again") in text
    for name in NAMES:
        assert (out / name).read_text() == (GOLDEN / name).read_text(), name
    assert seconds < 20, f"{seconds:.1f} s"  # discovery and description: ~5 s here
    with Arm.connect("KR60", cache=tmp_path / "cache") as arm:
        assert arm.urdf == (GOLDEN / "KR60.urdf").read_text()


@pytest.mark.slow
def test_urdf_twice_tours_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                               capsys: pytest.CaptureFixture[str]) -> None:
    """End to end against the embedded simulator: the first `usar-arm urdf` tours (about
    35 s), the second (same server, same settings) writes the same files from the cache in a
    few seconds."""
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))
    first, second = tmp_path / "first", tmp_path / "second"
    assert main(["urdf", "--robot", "KR60", "--out-dir", str(first), "--json"]) == EXIT_OK
    doc = json.loads(capsys.readouterr().out)
    assert doc["calibration_source"] == "tour"
    begin = time.perf_counter()
    assert main(["urdf", "--robot", "KR60", "--out-dir", str(second)]) == EXIT_OK
    seconds = time.perf_counter() - begin
    assert "calibrated description from the cache" in capsys.readouterr().out
    assert seconds < 20, f"{seconds:.1f} s"
    for name in NAMES:
        assert (second / name).read_bytes() == (first / name).read_bytes(), name
    entry = cache_folder(run_discovery(DescribeOptions()), DescribeOptions())
    assert latest_calibrated(entry, "KR60") is not None
