"""Every picture the README and the docs show is made by tools/pictures.py, records what made it
(a PNG text chunk: the command and a hash of its inputs), and is redrawn when its inputs change:
this test recomputes the hashes (drawing nothing) and names the stale pictures (issue 39: the
README's reachability picture dated from before the joint gap was closed)."""

from __future__ import annotations

import io
import re
import sys
from pathlib import Path

import pytest
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import pictures  # noqa: E402

pictures.load_hooks()
SHOWN = re.compile(r"!\[[^\]]*\]\(([^)\s]+\.png)\)")


def _shown() -> set[str]:
    """The PNGs the README and the docs pages show (markdown images), relative to the root."""
    out = set()
    for page in [ROOT / "README.md", *(ROOT / "docs").rglob("*.md")]:
        for target in SHOWN.findall(page.read_text()):
            out.add(str((page.parent / target).resolve().relative_to(ROOT)))
    return out


def test_every_picture_shown_is_made_by_the_pictures_tool() -> None:
    made = {p.path for p in pictures.PICTURES.values()}
    assert _shown() - made == set(), "pictures shown that tools/pictures.py does not make"
    assert made - _shown() == set(), "pictures made that no page shows"


def test_no_picture_is_stale() -> None:
    stale = [f"{p.path}: {why}" for p in pictures.PICTURES.values()
             if (why := pictures.staleness(p))]
    assert stale == [], ("run python tools/pictures.py --stale (make pictures):\n"
                         + "\n".join(stale))


def _png(path: Path, colour: tuple[int, int, int] = (10, 20, 30)) -> None:
    buffer = io.BytesIO()
    Image.new("RGB", (4, 3), colour).save(buffer, format="PNG")
    path.write_bytes(buffer.getvalue())


def test_a_record_round_trips_and_leaves_a_valid_png(tmp_path: Path) -> None:
    picture = tmp_path / "p.png"
    _png(picture)
    assert pictures.read_record(picture) is None
    pictures.write_record(picture, {"command": "draw it", "inputs": "sha256:1"})
    pictures.write_record(picture, {"command": "draw it", "inputs": "sha256:2"})  # (replaced)
    assert pictures.read_record(picture) == {"command": "draw it", "inputs": "sha256:2"}
    with Image.open(picture) as image:
        image.load()
        assert image.size == (4, 3) and image.getpixel((0, 0)) == (10, 20, 30)


def test_a_picture_is_stale_when_an_input_changes(tmp_path: Path) -> None:
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "a.txt").write_text("1")

    def make(out: Path, scratch: Path) -> None:
        _png(out)

    picture = pictures.Picture("img/x.png", "make x", ("data/*.txt",), make)
    assert pictures.staleness(picture, tmp_path) == "missing"
    pictures.draw(picture, tmp_path)
    assert pictures.staleness(picture, tmp_path) is None
    (tmp_path / "data" / "b.txt").write_text("2")
    assert pictures.staleness(picture, tmp_path) == "its inputs changed since it was drawn"
    pictures.draw(picture, tmp_path)
    (tmp_path / "data" / "a.txt").write_text("changed")
    assert pictures.staleness(picture, tmp_path) == "its inputs changed since it was drawn"
    pictures.draw(picture, tmp_path)
    other = pictures.Picture("img/x.png", "make x otherwise", ("data/*.txt",), make)
    assert "made by another command" in str(pictures.staleness(other, tmp_path))
    _png(tmp_path / "img" / "x.png")
    assert pictures.staleness(picture, tmp_path) == "records nothing of what made it"


def test_an_input_that_matches_nothing_is_an_error(tmp_path: Path) -> None:
    picture = pictures.Picture("x.png", "c", ("nothing/*.py",), lambda out, scratch: None)
    with pytest.raises(FileNotFoundError, match=r"x: input nothing/\*\.py matches no file"):
        pictures.inputs_hash(picture, tmp_path)


def test_a_second_picture_of_a_name_is_refused() -> None:
    taken = next(iter(pictures.PICTURES.values()))
    with pytest.raises(ValueError, match="registered already"):
        pictures.register(taken)
