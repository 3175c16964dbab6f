"""A drive's input files and waypoints: read when well formed, refused with file, line and
what was expected otherwise; waypoints outside the world or inside a box refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_arm.control.drive_inputs import check_in_world, load_script, parse_waypoints
from usar_arm.control.pursuit import Segment
from usar_arm.core.errors import FileFormatError, InvalidInputError
from usar_arm.core.vehicle_errors import OutsideWorldError
from usar_arm.core.world_file import load_scenery


@pytest.mark.parametrize(("name", "text"), [
    ("s.yaml", "- [2, 0.1, 0]\n- {duration: 1.5, v: 0, w: -0.3}\n"),
    ("s.csv", "# forward, then turn\nduration,v,w\n2,0.1,0\n1.5, 0, -0.3\n"),
])
def test_a_script_reads_as_yaml_or_csv(tmp_path: Path, name: str, text: str) -> None:
    (tmp_path / name).write_text(text)
    assert load_script(tmp_path / name) == (Segment(2, 0.1, 0), Segment(1.5, 0, -0.3))


@pytest.mark.parametrize(("name", "text", "line", "says"), [
    ("s.yaml", "- [2, 0.1, 0]\n- [1, 0.1]\n", 2, "3 finite numbers"),
    ("s.yaml", "- [2, 0.1, 0]\n- [0, 0.1, 0]\n", 2, "duration must be > 0"),
    ("s.yaml", "- [2, .nan, 0]\n", 1, "finite"),
    ("s.csv", "2,0.1,0\n2,x,0\n", 2, "expected duration"),
    ("s.yaml", "{duration: 2}\n", None, "non-empty list"),
])
def test_a_malformed_script_names_its_line(tmp_path: Path, name: str, text: str,
                                           line: int | None, says: str) -> None:
    (tmp_path / name).write_text(text)
    with pytest.raises(FileFormatError, match=says) as info:
        load_script(tmp_path / name)
    assert info.value.line == line


def test_waypoints_come_as_tokens_or_a_file(tmp_path: Path) -> None:
    assert parse_waypoints(["1,-2", "3.5,0"]) == ((1, -2), (3.5, 0))
    (tmp_path / "w.yaml").write_text("- [1, -2]\n- [3.5, 0]\n")
    (tmp_path / "w.csv").write_text("x,y\n1,-2\n3.5,0\n")
    assert parse_waypoints([str(tmp_path / "w.yaml")]) == ((1, -2), (3.5, 0))
    assert parse_waypoints([str(tmp_path / "w.csv")]) == ((1, -2), (3.5, 0))
    with pytest.raises(InvalidInputError, match="nan"):
        parse_waypoints(["nan,1"])


def test_waypoints_outside_the_rooms_or_inside_a_box_are_refused() -> None:
    rooms = load_scenery("rooms")
    check_in_world([(1, -1.5), (7, -5)], rooms, "rooms")
    with pytest.raises(OutsideWorldError, match="outside the world rooms") as info:
        check_in_world([(1, -1.5), (1, 3)], rooms, "rooms")  # y = 3: beyond the west wall
    assert info.value.index == 2
    with pytest.raises(OutsideWorldError, match="inside pillar"):
        check_in_world([(8, -6.5)], rooms, "rooms")
    with pytest.raises(OutsideWorldError, match="inside crate"):  # a rotated box
        check_in_world([(8.4, -2.2)], rooms, "rooms")
