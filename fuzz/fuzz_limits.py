"""Fuzz the ``--velocity-limits`` file reader (usar_arm.discover.limits.load_limits_file, with
usar_arm.core.yamlio and PyYAML), for a 6-joint arm named joint_a1..joint_a6.

Contract: any file content gives one dict of positive finite limits per joint, or raises
InvalidInputError (FileFormatError naming the file); nothing else escapes.

    python fuzz/fuzz_limits.py -max_total_time=60 build/fuzz/limits fuzz/corpus/limits
"""

from __future__ import annotations

import math

import atheris
from _harness import run, scratch_file

with atheris.instrument_imports(include=["usar_arm", "yaml"]):
    from usar_arm.core.errors import InvalidInputError
    from usar_arm.discover.limits import load_limits_file

FILE = scratch_file("limits.yaml")
NAMES = [f"joint_a{i}" for i in range(1, 7)]


def test_one_input(data: bytes) -> None:
    FILE.write_bytes(data)
    try:
        limits = load_limits_file(FILE, len(NAMES), NAMES)
    except InvalidInputError as exc:
        assert str(FILE) in str(exc), exc
        return
    assert len(limits) == len(NAMES)
    for entry in limits:
        for key, value in entry.items():
            assert key in ("velocity", "acceleration", "jerk"), key
            assert math.isfinite(value) and value > 0, (key, value)


if __name__ == "__main__":
    run(test_one_input, "limits.dict")
