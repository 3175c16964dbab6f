"""The USARSim line codec: round-trips, UDK's quirks, and malformed input."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.usarsim import strategies as S
from usar_arm.core.errors import ProtocolError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import format_message, parse_line, split_line
from usar_arm.usarsim.numbers import FULL, UDK, udk_float_string


@pytest.mark.parametrize("kind", sorted(S.ALL))
@settings(max_examples=80, deadline=None)
@given(data=st.data())
def test_every_message_type_round_trips_at_full_precision(kind: str, data: st.DataObject) -> None:
    msg = data.draw(S.ALL[kind])
    text = format_message(msg, FULL)
    assert text.endswith("\r\n") and "\r\n" not in text[:-2]
    assert parse_line(text) == msg


def _without_numbers(value: object) -> object:
    """The message with every float replaced by 0.0 (its structure and text fields only)."""
    if isinstance(value, float):
        return 0.0
    if isinstance(value, tuple):
        return tuple(_without_numbers(v) for v in value)
    if dataclasses.is_dataclass(value):
        return tuple((f.name, _without_numbers(getattr(value, f.name)))
                     for f in dataclasses.fields(value))
    return value


@settings(max_examples=300, deadline=None)
@given(S.messages)
def test_udk_number_formats_keep_the_structure(msg: m.Message) -> None:
    back = parse_line(format_message(msg, UDK))
    assert type(back) is type(msg)
    assert _without_numbers(back) == _without_numbers(msg)


@given(st.floats(min_value=-1e4, max_value=1e4, allow_nan=False))
def test_udk_numbers_read_back_within_their_resolution(v: float) -> None:
    f32_error = abs(v) * 2e-7 + 1e-30
    fixed = float(UDK.fixed(v))  # FloatString(p=3): truncated toward zero, in float32
    assert abs(fixed) <= abs(v) + f32_error
    assert abs(v) - abs(fixed) < 1e-3 + f32_error
    assert fixed == 0.0 or (fixed > 0) == (v > 0)
    assert abs(float(UDK.raw_vector([v])) - v) <= 0.005 + 1e-12 * abs(v)
    assert abs(float(UDK.scalar(v)) - v) <= 5e-5 + 1e-12 * abs(v)


@given(S.messages, st.sampled_from(["\r\n", "\n", "\r", ""]))
def test_any_line_terminator_parses_the_same(msg: m.Message, ending: str) -> None:
    text = format_message(msg).rstrip("\r\n") + ending
    assert parse_line(text) == msg


# ------------------------------------------------------------------------------ UDK quirks


def test_blocks_may_touch_without_a_space() -> None:
    line = ("GEO {Type Actuator} {Name KR60Arm} {Location 0.000,0.000,0.000} "
            "{Orientation 0.000,0.000,0.000}{Mount KR60} {Link 1} {Parent 0} "
            "{Location 0.070,0.010,-0.413} {Orientation 3.14,0.00,0.00}{Tip 0.05,0.00,0.00}")
    geo = parse_line(line)
    assert isinstance(geo, m.Geo)
    item = geo.items[0]
    assert item.mount == "KR60" and item.tip == (0.05, 0.0, 0.0)
    assert item.links == (m.LinkGeo(1, 0, (0.07, 0.01, -0.413), (3.14, 0.0, 0.0)),)


def test_whitespace_inside_blocks_is_trimmed_and_values_keep_spaces_and_commas() -> None:
    head, blocks = split_line("Com2 {  Key   88  } {Msg hello, big  world}")
    assert head == "Com2"
    assert [(b.key, b.value) for b in blocks] == [("Key", "88"), ("Msg", "hello, big  world")]


def test_command_words_and_keys_are_case_insensitive() -> None:
    msg = parse_line("getconf {type Actuator} {NAME KR60Arm}")
    assert msg == m.GetConf("Actuator", "KR60Arm")


def test_act_link_and_value_are_case_sensitive_as_in_udk() -> None:
    msg = parse_line("ACT {Name KR60Arm} {Link 0} {Value 0.5} {link 1} {value 2} "
                     "{Link 2} {Value -1}")
    assert isinstance(msg, m.Act)
    assert msg.targets == ((0, 0.5), (2, -1.0))
    assert msg.extra == (("link", "1"), ("value", "2"))


def test_platform_conf_keeps_name_before_type_and_the_trailing_space() -> None:
    line = "CONF {Name KR60} {Type StaticPlatform} {SteeringType None} {Mass 0} \r\n"
    msg = parse_line(line)
    assert msg == m.PlatformConf("KR60", "StaticPlatform",
                                 (("SteeringType", "None"), ("Mass", "0")))
    assert format_message(msg, UDK) == line


def test_repeated_link_groups_are_kept_in_order() -> None:
    msg = parse_line("ASTA {Time 1.5} {Name KR60Arm} {Link 1} {Value 0.1} {Link 2} {Value -0.2} "
                     "{Link 3} {Value 0.3}")
    assert isinstance(msg, m.Asta)
    assert msg.values == ((1, 0.1), (2, -0.2), (3, 0.3))


def test_ackermann_drive_reads_speed_and_steers_and_prints_them_back() -> None:
    line = "DRIVE {Speed 0.5} {FrontSteer -0.25} {RearSteer 0} {Normalized false}\r\n"
    msg = parse_line(line)
    assert msg == m.Drive(normalized=False, speed=0.5, front_steer=-0.25, rear_steer=0.0)
    assert msg.left is None and msg.right is None
    assert format_message(msg, UDK) == ("DRIVE {Speed 0.5000} {FrontSteer -0.2500} "
                                        "{RearSteer 0.0000} {Normalized false}\r\n")
    assert parse_line(format_message(msg)) == msg
    skid = parse_line("DRIVE {Left 1} {Right 2}")
    assert isinstance(skid, m.Drive) and skid.speed is None and skid.front_steer is None


def test_ut_era_keys_are_kept_not_dropped() -> None:
    msg = parse_line("CONF {Type Actuator} {Name TeleMaxArm} {Link 1} {JointType Revolute} "
                     "{MaxSpeed 0.17} {MaxTorque 300.00} {MinValue 1.00} {MaxValue 0.00} "
                     "{Stiffness 3}")
    assert isinstance(msg, m.Conf)
    link = msg.items[0].links[0]
    assert link.max_speed == 0.17 and link.max_torque == 300.0
    assert link.extra == (("Stiffness", "3"),)


def test_start_poses_reply_parses_all_names_in_one_block() -> None:
    msg = parse_line("NFO {StartPoses 2} {RobotStart1 1.50,-2.00,-0.10 0.00,0.00,1.57 "
                     "RobotStart2 4.00,0.00,-0.10 0.00,0.00,0.00}")
    assert isinstance(msg, m.StartPoses)
    assert msg.names == ("RobotStart1", "RobotStart2")
    assert msg.poses[0].location == (1.5, -2.0, -0.1)
    assert parse_line("NFO {StartPoses 0}") == m.StartPoses(())


def test_eff_bare_blocks_and_unknown_commands_are_kept() -> None:
    eff = parse_line("EFF {Time 3.2} {Type Gripper} {Name grip} {On}")
    assert isinstance(eff, m.Eff) and eff.extra == (("On", ""),)
    unknown = parse_line("MISSTA {Time 1} {Name arm} {Link 1} {Value 0} {Torque 0}")
    assert isinstance(unknown, m.Unknown) and unknown.head == "MISSTA"
    assert len(unknown.blocks) == 5


def test_vectors_with_spaces_after_commas_parse() -> None:
    msg = parse_line("INIT {ClassName USARBot.P3AT} {Name R1} {Location 0.76, 2.3, 1.8} "
                     "{Rotation 0, 0, 1.57}")
    assert isinstance(msg, m.Init)
    assert msg.location == (0.76, 2.3, 1.8) and msg.rotation == (0.0, 0.0, 1.57)


# ------------------------------------------------------------------------------ numbers


@pytest.mark.parametrize(("value", "expected"), [
    (-1.0049, "-1.004"), (0.07, "0.070"), (-0.0, "0.000"), (0.0999, "0.099"), (12.0, "12.000"),
    (-0.413, "-0.413"), (2.9999999, "3.000"),
])
def test_floatstring_truncates_in_float32_like_unrealscript(value: float, expected: str) -> None:
    assert udk_float_string(value, 3) == expected


def test_raw_vectors_round_to_two_decimals_and_never_print_minus_zero() -> None:
    assert UDK.raw_vector((0.048, -0.001, 3.14159)) == "0.05,0.00,3.14"


# ------------------------------------------------------------------------------ malformed


@pytest.mark.parametrize(("line", "column", "words"), [
    ("ASTA {Time 1} {Name arm", 14, "never closed"),
    ("ASTA {Time {1}}", 11, "do not nest"),
    ("ASTA {Time 1} } {Name a}", 14, "without a matching"),
    ("ASTA {Time 1} junk {Name a}", 14, "outside a block"),
    ("{Time 1}", 0, "command word"),
    ("", 0, "command word"),
    ("ASTA {} {Name a}", 5, "empty block"),
    ("GET CONF {Type Actuator}", 3, "single word"),
    ("ASTA {Time abc} {Name a}", 5, "expected a number"),
    ("ASTA {Time 1} {Name a} {Link x} {Value 1}", 23, "expected an integer"),
    ("GEO {Type Actuator} {Name a} {Link 1} {Parent 0} {Location 1,2} {Orientation 0,0,0}", 49,
     "expected a vector"),
    ("GEO {Type Actuator} {Name a} {Link 1} {Location 1,2,3} {Orientation 0,0,0}", 29,
     "no {Parent"),
    ("NFO {StartPoses 2} {Start1 0,0,0 0,0,0}", 19, "holds"),
    ("GETCONF {Name x}", 16, "needs {Type"),
    ("CONF {Type Actuator} {Link 1} {JointType Revolute}", 21, "expected {Name"),
])
def test_malformed_lines_raise_protocol_error_quoting_line_and_column(
        line: str, column: int, words: str) -> None:
    with pytest.raises(ProtocolError) as info:
        parse_line(line)
    assert info.value.line == line
    assert info.value.position == column
    assert words in str(info.value)
    assert line[:30] in str(info.value)


def test_asta_joints_reads_an_arms_links_in_configuration_order_or_none_when_one_is_missing(
        ) -> None:
    asta = parse_line("ASTA {Time 1.0} {Name KR60Arm} {Link 2} {Value -0.5} {Link 1} {Value 0.25}")
    assert isinstance(asta, m.Asta)
    assert asta.joints((1, 2)) == (0.25, -0.5)
    assert asta.joints((2,)) == (-0.5,)
    assert asta.joints((1, 3)) is None
    assert asta.missing((1, 3, 2, 4)) == (3, 4) and asta.missing((2, 1)) == ()
