"""The yourdfpy reader gives the same chain as the hand-written cylinder reader on every
description usar-arm ships (as-learnt and calibrated KR60 and Fanuc): switching readers changes
no model."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_arm.urdf.description_reader import parse_urdf as new_reader
from usar_arm.urdf.reader import parse_urdf as old_reader

GENERATED = Path(__file__).resolve().parents[2] / "robots" / "generated"


@pytest.mark.parametrize("path", sorted(GENERATED.rglob("*.urdf")), ids=lambda p: p.name)
def test_the_new_reader_reads_what_usar_arm_writes_as_the_old_one_did(path: Path) -> None:
    text = path.read_text()
    assert new_reader(text, str(path)) == old_reader(text, str(path))
