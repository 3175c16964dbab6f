"""Fuzz the trajectory file reader (usar_arm.control.trajectory: Trajectory.load,
load_with_executed), what ``usar-arm execute`` and the picture commands read.

Contract: any file content loads or raises InvalidInputError (FileFormatError naming the file
and field). A trajectory that loads can be sampled anywhere, and saves and re-loads unchanged.

    python fuzz/fuzz_trajectory.py -max_total_time=60 build/fuzz/trajectory fuzz/corpus/trajectory
"""

from __future__ import annotations

import json

import atheris
import numpy as np
from _harness import run, scratch_file

with atheris.instrument_imports(include=["usar_arm"]):
    from usar_arm.control.trajectory import Trajectory, load_with_executed
    from usar_arm.core.errors import InvalidInputError

FILE = scratch_file("trajectory.json")


def test_one_input(data: bytes) -> None:
    FILE.write_bytes(data)
    try:
        traj, executed = load_with_executed(FILE)
    except InvalidInputError as exc:
        assert str(FILE) in str(exc), exc
        return
    n = len(traj.joint_names)
    for time in (-1.0, 0.0, traj.duration / 3, traj.duration, traj.duration + 1):
        q, qd = traj.at(time)
        assert q.shape == qd.shape == (n,) and np.all(np.isfinite(q)), (time, q)
    if executed is not None:
        assert executed.q.shape == (len(executed.t), n)
    back = Trajectory.from_json(json.loads(json.dumps(traj.to_json())), "<re-saved>")
    for key in ("t", "q", "qd", "qdd", "waypoints"):
        assert np.array_equal(getattr(back, key), getattr(traj, key)), key


if __name__ == "__main__":
    run(test_one_input, "trajectory.dict")
