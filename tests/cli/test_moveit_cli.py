"""``usar-arm moveit-config``: the ROS 2 distribution it writes for (``ompl_planning.yaml``'s
keys differ between Humble and Jazzy; Jazzy by default), and its --out checked before any work
as tesseract-config's is."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_INVALID_INPUT, EXIT_OK, EXIT_USAGE
from usar_arm.urdf.moveit_planning import DEFAULT_DISTRO


@pytest.mark.parametrize("distro", [None, "humble", "jazzy"])
def test_the_ros_distro_chooses_the_pipeline_s_format(
        distro: str | None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "kr60_moveit_config"
    chosen = ["--ros-distro", distro] if distro else []
    assert main(["moveit-config", "--no-calibrate", "--out", str(out), "--json",
                 *chosen]) == EXIT_OK
    doc = json.loads(capsys.readouterr().out)
    expected = distro or DEFAULT_DISTRO
    assert DEFAULT_DISTRO == "jazzy"  # the current LTS, as the help and the docs say
    assert doc["ros_distro"] == expected and doc["calibrated"] is False
    pipeline = yaml.safe_load((out / "config" / "ompl_planning.yaml").read_text())
    key = "planning_plugin" if expected == "humble" else "planning_plugins"
    assert key in pipeline and ("response_adapters" in pipeline) == (expected == "jazzy")
    assert f"--ros-distro {expected}" in (out / ".setup_assistant").read_text()


def test_an_unknown_ros_distro_is_a_usage_error(tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["moveit-config", "--ros-distro", "iron", "--out", str(tmp_path / "p")])
    assert exit_.value.code == EXIT_USAGE
    assert list(tmp_path.iterdir()) == []


def test_a_file_in_the_way_is_refused_before_any_work(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "a_file").write_text("mine\n")
    code = main(["moveit-config", "--out", str(tmp_path / "a_file" / "kr60_moveit_config")])
    assert code == EXIT_INVALID_INPUT
    err = capsys.readouterr().err
    assert "is a file, so no folder can be made under it" in err and "discovering" not in err
    assert [p.name for p in tmp_path.iterdir()] == ["a_file"]
