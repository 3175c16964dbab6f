"""The cell's lines on the wire: CONTROL, the WorldController's GetSTA reply in UDK's exact
(unclosed) form, EFF's glued ``}{ToolType``, the ToolChanger CONF's glued
``}{PositionTolerance``, effector GEO's raw vectors, and the GripTruth and Contact extensions:
golden strings from the UDK code, round trips, and hypothesis properties of the parsers."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.usarsim import strategies as S
from usar_arm.core.errors import ProtocolError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.cell_codec import parse_wc_status
from usar_arm.usarsim.codec import format_message, parse_line
from usar_arm.usarsim.numbers import FULL, UDK

# WorldController.GetSTA: "{Name " $ n $ "} {Size " $ s $ "} {Location " $ l $ " {Memory {" $
# mem $ "} {Rotation " $ r $ "}", vectors by Str_LengthVectorFromUU (FloatString, 4 decimals).
GETSTA = ("STA {Name part} {Size 0.1200,0.1200,0.1000} {Location 1.4500,0.4500,-0.7500 "
          "{Memory {} {Rotation 0.0000,0.0000,1.5707} {Name bin} {Size 0.4000,0.3000,0.2000} "
          "{Location 1.4500,-0.5000,-0.8000 {Memory {rfid 7} {Rotation 0.0000,0.0000,0.0000}")


def test_get_sta_reply_is_udks_unclosed_form_and_parses_back() -> None:
    msg = parse_line(GETSTA + "\r\n")
    assert msg == m.WcStatus((
        m.WcObjectStatus("part", (0.12, 0.12, 0.1), (1.45, 0.45, -0.75), "", (0.0, 0.0, 1.5707)),
        m.WcObjectStatus("bin", (0.4, 0.3, 0.2), (1.45, -0.5, -0.8), "rfid 7", (0.0, 0.0, 0.0))))
    assert format_message(msg, UDK) == GETSTA + "\r\n"
    assert parse_line("STA") == m.WcStatus() and format_message(m.WcStatus(), UDK) == "STA\r\n"


def test_get_sta_closed_form_is_read_too() -> None:
    closed = ("STA {Name part} {Size 0.12,0.12,0.10} {Location 1.45,0.45,-0.75} "
              "{Memory tag} {Rotation 0,0,0}")
    assert parse_line(closed) == m.WcStatus((m.WcObjectStatus(
        "part", (0.12, 0.12, 0.1), (1.45, 0.45, -0.75), "tag", (0.0, 0.0, 0.0)),))


@pytest.mark.parametrize("bad", [
    "STA {Name part} {Size 1,2} {Location 1,2,3 {Memory {} {Rotation 0,0,0}",
    "STA {Name part} {Size 1,2,3} {Location 1,2,3 {Memory {} {Rotation 0,0,nan}",
    "STA {Name part} {Size 1,2,3} {Location 1,2,3 {Memory {} {Rotation 0,0,0} junk",
    "STA {Name part} {Size 1,2,3}"])
def test_a_broken_get_sta_reply_is_refused_with_its_column(bad: str) -> None:
    with pytest.raises(ProtocolError):
        parse_line(bad)


def test_a_robots_sta_is_still_a_robot_status() -> None:
    assert parse_line("STA {Time 1.5000} {Battery 99999} {Type StaticPlatform}") == \
        m.Sta(1.5, 99999, "StaticPlatform")


def test_effector_golden_strings() -> None:
    eff = m.Eff("ToolChanger", "toolchange", 3.2,
                (("Status", "CLOSED"), ("ToolType", "Gripper"), ("Tool", "KR60gripper")))
    assert format_message(eff, UDK) == ("EFF {Time 3.2000} {Type ToolChanger} {Name toolchange}"
                                        " {Status CLOSED}{ToolType Gripper} {Tool KR60gripper}"
                                        "\r\n")
    assert eff.status == "CLOSED" and eff.get("tool") == "KR60gripper"
    assert format_message(m.Eff("Gripper", "KR60gripper", 3.2, (("Status", "OPEN"),)), UDK) == \
        "EFF {Time 3.2000} {Type Gripper} {Name KR60gripper} {Status OPEN}\r\n"
    conf = m.Conf("ToolChanger", (m.ConfItem("toolchange", (
        ("PositionTolerance", "0.5000"), ("AngleTolerance", "0.5000"), ("Opcode", "Close"),
        ("Opcode", "Open"))),))
    assert format_message(conf, UDK) == (
        "CONF {Type ToolChanger} {Name toolchange}{PositionTolerance 0.5000} {AngleTolerance "
        "0.5000} {Opcode Close} {Opcode Open}\r\n")
    geo = m.Geo("Gripper", (m.GeoItem("KR60gripper", (0.0, 0.0, 0.0), (0.0, 1.57, 0.0),
                                      mount="toolchange", tip=(0.0, 0.0, 0.183)),))
    assert format_message(geo, UDK) == (
        "GEO {Type Gripper} {Name KR60gripper} {Location 0.00,0.00,0.00} {Orientation "
        "0.00,1.57,0.00}{Mount toolchange}{Tip 0.00,0.00,0.18}\r\n")
    for msg in (eff, conf, geo):
        assert parse_line(format_message(msg, FULL)) == msg


def test_extension_lines() -> None:
    grip = m.GripTruth("KR60gripper", True, "part", 12.3)
    assert format_message(grip, UDK) == ("SEN {Time 12.3000} {Type GripTruth} {Name KR60gripper} "
                                         "{Holding True} {Object part}\r\n")
    assert format_message(m.GripTruth("KR60gripper", False, None, 1.0), UDK) == (
        "SEN {Time 1.0000} {Type GripTruth} {Name KR60gripper} {Holding False}\r\n")
    report = m.ContactReport("KR60", (m.ContactPair("link:KR60/Joint6", "scenery:table_top",
                                                    1.201, 1.299, 0.0042, 99),), 1.3)
    assert format_message(report, UDK) == (
        "SEN {Time 1.3000} {Type Contact} {Name KR60} {Count 1} {Pair link:KR60/Joint6 "
        "scenery:table_top} {First 1.2010} {Last 1.2990} {Depth 0.0042} {Steps 99}\r\n")
    assert format_message(m.ContactReport("KR60", (), 1.3), UDK) == \
        "SEN {Time 1.3000} {Type Contact} {Name KR60} {Count 0}\r\n"
    with pytest.raises(ProtocolError, match="Count says 2"):
        parse_line("SEN {Type Contact} {Name KR60} {Count 2} {Pair a b} {First 1} {Last 1} "
                   "{Depth 0} {Steps 1}")
    with pytest.raises(ProtocolError, match=r"expected \{Pair a b\}"):
        parse_line("SEN {Type Contact} {Name KR60} {Count 1} {Pair a} {First 1} {Last 1} "
                   "{Depth 0} {Steps 1}")


def test_control_lines() -> None:
    msg = m.Control("Create", "part", "WCCrate", "1.45,0.45,-0.75", "0,0,0", "0.4,0.4,0.4",
                    "RigidBody", "false", "tag")
    line = format_message(msg, UDK)
    assert line == ("CONTROL {Type Create} {Name part} {ClassName WCCrate} {Location "
                    "1.45,0.45,-0.75} {Rotation 0,0,0} {Scale 0.4,0.4,0.4} {Physics RigidBody} "
                    "{Permanent false} {Memory tag}\r\n")
    assert parse_line(line) == msg
    assert parse_line("control {type KillAll} {MinPos 1,2} {Odd x}") == m.Control(
        "KillAll", min_pos="1,2", extra=(("Odd", "x"),))


# ------------------------------------------------------------------ properties

text = st.text(alphabet=st.characters(whitelist_categories=("Lu", "Ll", "Nd"),
                                      whitelist_characters="_-."), min_size=1, max_size=12)
memo = st.text(alphabet=st.characters(whitelist_categories=("Lu", "Ll", "Nd", "Zs"),
                                      whitelist_characters="_-.:"), max_size=16).map(str.strip)
udk4 = st.integers(-(10**9), 10**9).map(lambda k: k / 10**4)
vec4 = st.tuples(udk4, udk4, udk4)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.builds(m.WcObjectStatus, text, vec4, vec4, memo, vec4), max_size=5))
def test_get_sta_replies_round_trip_in_udks_form(objects: list[m.WcObjectStatus]) -> None:
    """UDK's FloatString truncates in float32: a reply reads back within its last digit."""
    msg = m.WcStatus(tuple(objects))
    back = parse_line(format_message(msg, UDK))
    assert isinstance(back, m.WcStatus)
    for got, want in zip(back.objects, objects, strict=True):
        assert (got.name, got.memory) == (want.name, want.memory)
        for a, b in ((got.size, want.size), (got.location, want.location),
                     (got.rotation, want.rotation)):
            assert max(abs(x - y) for x, y in zip(a, b, strict=True)) <= 1.1e-4 * max(
                1.0, *map(abs, b))


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=80))
def test_the_get_sta_parser_refuses_or_parses_anything_with_no_other_error(junk: str) -> None:
    try:
        msg = parse_wc_status("STA " + junk)
    except ProtocolError:
        return
    assert isinstance(msg, m.WcStatus)


@pytest.mark.parametrize("kind", ["Control", "WcStatus", "ContactReport", "GripTruth"])
@settings(max_examples=100, deadline=None)
@given(data=st.data())
def test_the_cell_messages_round_trip_at_full_precision(kind: str,
                                                        data: st.DataObject) -> None:
    msg = data.draw(S.ALL[kind])
    assert parse_line(format_message(msg, FULL)) == msg
