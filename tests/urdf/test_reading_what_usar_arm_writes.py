"""Every description usar-arm ships (as-learnt and calibrated KR60 and Fanuc) reads back to the
chain it was written from: written again, it gives the file's lines byte for byte (the joints
breadth first; a material only a frame link had is not read back, as the hand-written reader
did not), and reading that gives the same chain, so reading with yourdfpy changed no model (the
hand-written reader's chains were compared equal before it was removed)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from usar_arm.urdf.description_reader import parse_urdf
from usar_arm.urdf.writer import urdf_text

GENERATED = Path(__file__).resolve().parents[2] / "robots" / "generated"


@pytest.mark.parametrize("path", sorted(GENERATED.rglob("*.urdf")),
                         ids=lambda p: p.relative_to(GENERATED).as_posix())
def test_a_shipped_description_reads_back_to_its_own_lines(path: Path) -> None:
    text = path.read_text()
    chain, notes = parse_urdf(text, str(path))
    body = re.sub(r"<!--.*?-->\n", "", text, flags=re.S)
    written = urdf_text(chain)
    unread = set(body.splitlines()) - set(written.splitlines())
    assert set(written.splitlines()) <= set(body.splitlines())
    assert all(line.startswith("  <material ") for line in unread)
    assert parse_urdf(written) == (chain, notes) and notes == []
