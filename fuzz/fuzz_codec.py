"""Fuzz the USARSim line codec (usar_arm.usarsim.codec, numbers) with atheris.

Contract: any bytes, decoded as the client and the simulator decode them (UTF-8, errors
replaced), whole and cut at every CR/LF, either parse into a message or raise ProtocolError
that points inside the line. A parsed line must format again in both number styles, re-parse,
and be a fixpoint after that one round trip.

    python fuzz/fuzz_codec.py -max_total_time=60 build/fuzz/codec fuzz/corpus/codec
"""

from __future__ import annotations

import re

import atheris
from _harness import run

with atheris.instrument_imports(include=["usar_arm"]):
    from usar_arm.core.errors import ProtocolError
    from usar_arm.usarsim import cell_messages as cm
    from usar_arm.usarsim import messages as m
    from usar_arm.usarsim.codec import format_message, parse_line
    from usar_arm.usarsim.numbers import FULL, UDK

PARTS = (m.StartPose, m.LinkConf, m.ConfItem, m.LinkGeo, m.GeoItem, cm.WcObjectStatus,
         cm.ContactPair)
"""The messages' components: never what a line parses into."""
TYPES = tuple(t for mod in (m, cm) for t in vars(mod).values()
              if isinstance(t, type) and t.__module__ == mod.__name__ and t not in PARTS)
"""What a line may parse into: the messages of the wire and of a cell (WorldController,
contacts, grip truth)."""


def check(text: str) -> None:
    """One line through parse_line, and a parsed line through format_message and back."""
    try:
        msg = parse_line(text)
    except ProtocolError as exc:
        assert exc.line == text.rstrip("\r\n"), (exc.line, text)
        assert 0 <= exc.position <= len(exc.line), exc.position
        return
    assert isinstance(msg, TYPES), type(msg)
    format_message(msg, UDK)  # must not raise whatever the numbers are
    if "\r" in text.rstrip("\r\n") or "\n" in text.rstrip("\r\n"):
        return  # not one wire line
    again = parse_line(format_message(msg, FULL))
    assert type(again) is type(msg), (msg, again)
    assert parse_line(format_message(again, FULL)) == again, again


def test_one_input(data: bytes) -> None:
    text = data.decode("utf-8", "replace")
    check(text)
    for piece in re.split("[\r\n]", text):
        if piece.strip():
            check(piece)


if __name__ == "__main__":
    run(test_one_input, "codec.dict")
