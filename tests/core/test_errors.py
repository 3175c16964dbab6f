"""The error tree's one mechanism for evidence (usar_arm.core.errors.UsarArmError): an error
declares its evidence as dataclass fields and says it in message(); the evidence is what the
caller had when it raised; an error crosses a process boundary (pickle) whole."""

from __future__ import annotations

import dataclasses
import inspect
import pickle

import numpy as np
import pytest

from usar_arm.core import attach_errors, cell_errors, errors, job_errors, vehicle_errors
from usar_arm.core.errors import UsarArmError

MODULES = (errors, vehicle_errors, job_errors, cell_errors, attach_errors)
SAMPLES: list[UsarArmError] = [
    errors.FileFormatError("scene.yaml", "expected a mapping", 3, "objects"),
    errors.ProtocolError("ASTA {Time 1" + "x" * 300, 250, "expected '}'"),
    errors.UnknownComponentError("GETGEO {Type Gripper}", 2.0, ["Camera", "Arm"]),
    errors.UnknownStartError("PlayerStart9", ["PlayerStart0"]),
    errors.JointLimitError("joint_a2", 2.1, -1.0, 1.5),
    errors.StartInCollisionError([("link_2", "table")]),
    errors.LinBlockedError(0.25, np.array([0.5, 0.0, 1.25]), "collision: link_6-wall"),
    errors.ExecutionAbortedError("lost", "joint_a1", 0.12, 3.5),
    vehicle_errors.NonFiniteCommandError({"v": float("inf"), "w": 0.5}),
    job_errors.ResumeMismatchError("out", None, "k2", ["problems"]),
    cell_errors.GripError("vacuum", "pick", "a part on the cup", "nothing"),
    attach_errors.AttachError("box", "no link 'tool9' to attach it to", ["tool0"]),
    cell_errors.PlacementError("the part lies 4.0 mm from its place"),
    errors.TimingError("ruckig: limits inconsistent"),
]


def _error_classes() -> list[type[UsarArmError]]:
    return [c for m in MODULES for _, c in inspect.getmembers(m, inspect.isclass)
            if issubclass(c, UsarArmError) and c.__module__ == m.__name__]


def _evidence(error: UsarArmError) -> dict[str, object]:
    return {k: v for k, v in vars(error).items() if not k.startswith("_")}


@pytest.mark.parametrize("error", SAMPLES, ids=lambda e: type(e).__name__)
def test_an_error_survives_pickling_with_its_text_and_evidence(error: UsarArmError) -> None:
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is type(error)
    assert str(back) == str(error) and back.args == error.args
    assert repr(_evidence(back)) == repr(_evidence(error))
    assert back.exit_code == error.exit_code


def test_the_evidence_is_what_the_caller_had_when_it_raised() -> None:
    known = ["PlayerStart0", "PlayerStart1"]
    values = {"v": float("nan")}
    start = errors.UnknownStartError("PlayerStart9", known)
    command = vehicle_errors.NonFiniteCommandError(values)
    known.append("PlayerStart2")
    values["w"] = 1.0
    assert start.known == ("PlayerStart0", "PlayerStart1")
    assert command.values == {"v": values["v"]}
    assert str(start) == ("unknown start position 'PlayerStart9'; the server offers: "
                          "PlayerStart0, PlayerStart1")
    point = errors.LinBlockedError(0.5, np.array([1.0, 2.0, 3.0]), "r").point_m
    assert point == (1.0, 2.0, 3.0) and all(type(x) is float for x in point)


def test_an_error_keeps_the_exceptions_identity_and_repr() -> None:
    a, b = errors.NoPathError("RRTConnect", 5.0), errors.NoPathError("RRTConnect", 5.0)
    assert a != b and len({a, b}) == 2  # equal evidence, two failures
    assert repr(a) == "NoPathError('RRTConnect found no collision-free path within 5 s')"


def test_every_error_that_builds_its_message_declares_its_evidence_as_fields() -> None:
    """No hand-written store-and-format constructor is left, but the one that specialises its
    parent's (an unknown component is a timeout with a hint)."""
    specialised = {errors.UnknownComponentError}
    for cls in _error_classes():
        if "message" in vars(cls) and cls is not UsarArmError:
            assert dataclasses.is_dataclass(cls), cls.__name__
        if "__init__" in vars(cls) and cls not in specialised:
            assert dataclasses.is_dataclass(cls), f"{cls.__name__} writes its own __init__"
