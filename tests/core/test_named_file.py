"""A shipped name or a file (usar_arm.core.named_file): a bare word is a shipped world or scene
whatever the working folder holds, a path is what is written as one (a separator or a suffix),
and an error says what was tried (issue 39: a folder or file named like a shipped world or
scene shadowed it, with errors that contradicted themselves)."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_arm.core.errors import FileFormatError
from usar_arm.core.named_file import Named, looks_like_path, resolve_name
from usar_arm.core.world_file import load_scenery
from usar_arm.planning.scene_file import load_scene

SHIPPED = ("empty", "table")


@pytest.fixture
def here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize(("text", "path"), [
    ("table", False), ("my_scene", False), ("table.yaml", True), ("./table", True),
    ("scenes/table", True), ("/abs/table", True), ("cell.v2", True),
])
def test_a_path_is_what_is_written_as_one(text: str, path: bool) -> None:
    assert looks_like_path(text) is path


def test_a_shipped_name_is_not_hidden_by_a_folder_or_a_file_of_that_name(here: Path) -> None:
    (here / "table").mkdir()
    (here / "empty").write_text("not a scene\n")
    assert resolve_name("table", "scene", SHIPPED) == Named("table", shipped="table")
    assert resolve_name("empty", "scene", SHIPPED) == Named("empty", shipped="empty")


def test_a_file_of_a_shipped_name_is_named_as_a_path(here: Path) -> None:
    (here / "table").write_text("x\n")
    assert resolve_name("./table", "scene", SHIPPED) == Named("./table", path=Path("table"))
    assert resolve_name(Path("table"), "scene", SHIPPED).path == Path("table")


def test_a_bare_word_that_is_no_shipped_name_is_the_file_here(here: Path) -> None:
    (here / "cell").write_text("x\n")
    assert resolve_name("cell", "scene", SHIPPED) == Named("cell", path=Path("cell"))


@pytest.mark.parametrize(("given", "problem"), [
    ("nosuch", r"nosuch: no shipped scene of that name \(empty, table\) and no such file$"),
    ("folder", r"no shipped scene of that name \(empty, table\) and no such file \(it is a "
               r"folder\)"),
    ("./folder", r"is a folder, not a scene file \(a name without a folder or suffix names a "
                 r"shipped scene: empty, table\)"),
    ("nosuch.yaml", r"no such scene file \(a name without a folder or suffix names a shipped "
                    r"scene: empty, table\)"),
    ("x" * 300 + ".yaml", "not a usable file name"),
])
def test_what_names_nothing_says_what_was_tried(here: Path, given: str, problem: str) -> None:
    (here / "folder").mkdir()
    with pytest.raises(FileFormatError, match=problem):
        resolve_name(given, "scene", SHIPPED)


def test_scenes_and_worlds_follow_the_rule(here: Path) -> None:
    for name in ("table", "default", "rooms"):
        (here / name).mkdir()
    (here / "shelf").write_text("name: mine\nobjects: []\n")
    assert load_scene("table").name == "table" and len(load_scene("table").objects) > 0
    assert load_scene("shelf").name == "shelf"
    assert load_scene("./shelf").name == "mine"
    assert len(load_scenery("default").boxes) >= 0 and len(load_scenery("rooms").boxes) == 13
    with pytest.raises(FileFormatError, match="is a folder, not a world file"):
        load_scenery("./rooms")
    with pytest.raises(FileFormatError, match="is a folder, not a scene file"):
        load_scene("./table")
