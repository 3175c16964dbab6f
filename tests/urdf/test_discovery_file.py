"""A description's discovery.json is read in one place (usar_arm.urdf.discovery_file): the wire
facts the Robot, the facade and the calibration take from it, as the committed KR60's file has
them, the defaults of a description without them, and a clear error for a broken file."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from usar_arm.core.errors import FileFormatError
from usar_arm.planning.robot import robot_from_files
from usar_arm.urdf.discovery_file import WireFacts, discovery_document, wire_facts

KR60 = Path(__file__).resolve().parents[2] / "robots" / "generated" / "KR60.discovery.json"


def test_the_kr60s_wire_facts_are_what_its_file_says() -> None:
    doc = discovery_document({KR60.name: KR60.read_text(), "KR60.urdf": "<robot/>"})
    assert doc is not None
    facts = wire_facts(doc)
    assert (facts.actuator, facts.links, facts.tip_sensor) == (
        "KR60Arm", (1, 2, 3, 4, 5, 6), "KR60ArmTipTruth")
    assert facts.tip_resolution_m == 0.01 and facts.frames["tool0"] == "tool0"


def test_the_robot_read_from_files_carries_the_same_facts() -> None:
    robot = robot_from_files(KR60.with_name("KR60.urdf"))
    facts = wire_facts(json.loads(KR60.read_text()))
    assert (robot.actuator, robot.wire_links, robot.tip_sensor) == (
        facts.actuator, facts.links, facts.tip_sensor)


def test_a_description_without_the_file_has_none_and_an_empty_document_the_defaults() -> None:
    assert discovery_document({"X.urdf": "<robot/>"}) is None
    assert discovery_document({"X.discovery.json": "{}"}, stem="Y") is None
    assert wire_facts({}) == WireFacts()


@pytest.mark.parametrize(("text", "problem"), [
    ('{"chain": ', r"X\.discovery\.json:1: not JSON"),
    ("[1, 2]", "expected a JSON object, got list"),
])
def test_a_broken_file_is_named_with_its_problem(text: str, problem: str) -> None:
    with pytest.raises(FileFormatError, match=problem):
        discovery_document({"X.discovery.json": text})
