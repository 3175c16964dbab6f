"""Properties of the USARSim line codec, over generated messages and generated garbage.

Identities (``parse`` = :func:`parse_line`, ``format`` = :func:`format_message`):

* **FULL style, every message type**: ``parse(format(m, FULL)) == m`` and, on text,
  ``format(parse(L), FULL) == L`` for ``L = format(m, FULL)`` (the text check also catches a lost
  ``-0.0``). Domain (``strategies.WIDE``): every finite float64, integers up to +-2**128, values
  that are trimmed text without ``{``, ``}``, CR or LF, single-word names and keys, and extra
  blocks whose keys are not keys the message type models (an extra ``{Link 5}`` followed by an
  extra ``{Value 3}`` *is* a Link/Value pair on the wire).
* **UDK style, numbers UDK prints exactly, every message type**: ``parse(format(m, UDK)) == m``
  and ``format(parse(L), UDK) == L``. Domain (``strategies.UDK_EXACT``): raw scalars (Time,
  Value, CONF limits) are 4-decimal numbers, raw vectors 2-decimal numbers, FloatString vectors
  (GEO locations, GroundTruth poses) multiples of 1/8 within +-2**20.
* **UDK style, any number in float32 range**: ``parse(format(m, UDK)) == udk_quantized(m)``: each
  number comes back as its field's print kind quantises it (FloatString: truncated in float32 to
  3 decimals; raw vectors: rounded to 2; raw scalars: rounded to 4). Text is *not* a fixpoint for
  FloatString fields: re-printing a read-back ``3.807`` gives ``3.806``, as UDK's float32
  truncation would (the ``-1.005 -> -1.004`` of the reference).

Robustness: any byte string, decoded as the client and the simulator decode it (UTF-8 with
replacement), and any of its CR/LF-separated pieces, either parses or raises ProtocolError; a line
that parses can be sent again (it formats and re-parses), and one round trip makes it canonical.
The slow test runs >= 100,000 cases mixing random bytes, random text and mutated real lines
(``fuzz/corpus/codec``).
"""

from __future__ import annotations

import dataclasses
import random
import re
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from tests.usarsim import strategies as S
from usar_arm.core.errors import ProtocolError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import format_message, parse_line
from usar_arm.usarsim.numbers import FULL, UDK, udk_float_string

CORPUS = Path(__file__).resolve().parents[2] / "fuzz" / "corpus" / "codec"
MESSAGE_TYPES = (m.GameInfo, m.StartPoses, m.GetStartPoses, m.Init, m.GetConf, m.GetGeo, m.Act,
                 m.Set, m.Drive, m.Conf, m.PlatformConf, m.Geo, m.Asta, m.Sta, m.Sen,
                 m.RangeScan, m.Ins, m.Odometry, m.Eff, m.Unknown, m.Control, m.WcStatus,
                 m.ContactReport, m.GripTruth)


def test_the_strategies_cover_every_message_type() -> None:
    assert set(S.WIDE) == set(S.UDK_EXACT) == set(S.UDK_ANY) == {t.__name__ for t in MESSAGE_TYPES}


# ------------------------------------------------------------------------------ identities


@pytest.mark.parametrize("kind", sorted(S.WIDE))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_full_precision_round_trips_every_message_exactly(kind: str, data: st.DataObject) -> None:
    msg = data.draw(S.WIDE[kind])
    text = format_message(msg, FULL)
    assert text.endswith("\r\n") and "\r" not in text[:-2] and "\n" not in text[:-2]
    back = parse_line(text)
    assert back == msg
    assert format_message(back, FULL) == text


@pytest.mark.parametrize("kind", sorted(S.UDK_EXACT))
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_udk_style_round_trips_numbers_it_can_print_exactly(kind: str,
                                                           data: st.DataObject) -> None:
    msg = data.draw(S.UDK_EXACT[kind])
    text = format_message(msg, UDK)
    back = parse_line(text)
    assert back == msg
    assert format_message(back, UDK) == text


def _q(kind: str, value: object) -> object:
    """A number (or vector, or None) as the UDK print kind ``kind`` returns it."""
    quantize = {"scalar": UDK.quantize_scalar, "raw": UDK.quantize_raw,
                "fixed": UDK.quantize_fixed,
                "fixed2": lambda v: float(UDK.fixed_at(v, 2)),
                "fixed4": lambda v: float(UDK.fixed_at(v, 4))}[kind]
    if value is None:
        return None
    if isinstance(value, tuple):
        return tuple(quantize(v) for v in value)
    return quantize(value)  # type: ignore[arg-type]


def udk_quantized(msg: m.Message) -> m.Message:
    """The message a client reads back from ``format_message(msg, UDK)``: each number in the
    print kind of its field (usar_arm.usarsim.numbers)."""
    r = dataclasses.replace
    if isinstance(msg, m.GameInfo):
        return r(msg, time_limit=_q("scalar", msg.time_limit))
    if isinstance(msg, m.StartPoses):
        return r(msg, poses=tuple(r(p, location=_q("raw", p.location),
                                    rotation=_q("raw", p.rotation)) for p in msg.poses))
    if isinstance(msg, m.Init):
        return r(msg, location=_q("raw", msg.location), rotation=_q("raw", msg.rotation))
    if isinstance(msg, m.Act):
        return r(msg, targets=tuple((i, _q("scalar", v)) for i, v in msg.targets))
    if isinstance(msg, m.Drive):
        return r(msg, left=_q("scalar", msg.left), right=_q("scalar", msg.right),
                 speed=_q("scalar", msg.speed), front_steer=_q("scalar", msg.front_steer),
                 rear_steer=_q("scalar", msg.rear_steer))
    if isinstance(msg, m.Conf):
        return r(msg, items=tuple(r(it, links=tuple(
            r(ln, max_torque=_q("scalar", ln.max_torque), min_value=_q("scalar", ln.min_value),
              max_value=_q("scalar", ln.max_value), max_speed=_q("scalar", ln.max_speed))
            for ln in it.links)) for it in msg.items))
    if isinstance(msg, m.Geo):
        return r(msg, items=tuple(r(
            it, location=_q("fixed", it.location), orientation=_q("fixed", it.orientation),
            tip=_q("raw", it.tip),
            links=tuple(r(ln, location=_q("fixed", ln.location),
                          orientation=_q("raw", ln.orientation)) for ln in it.links))
            for it in msg.items))
    if isinstance(msg, m.Asta):
        return r(msg, time=_q("scalar", msg.time),
                 values=tuple((i, _q("scalar", v)) for i, v in msg.values))
    if isinstance(msg, m.Sta):
        return r(msg, time=_q("scalar", msg.time))
    if isinstance(msg, m.Sen):
        return r(msg, time=_q("scalar", msg.time), location=_q("fixed", msg.location),
                 orientation=_q("fixed", msg.orientation))
    if isinstance(msg, m.RangeScan):
        return r(msg, time=_q("scalar", msg.time), resolution=_q("fixed4", msg.resolution),
                 fov=_q("fixed4", msg.fov), ranges=_q("fixed2", msg.ranges))
    if isinstance(msg, m.Ins):
        return r(msg, time=_q("scalar", msg.time), location=_q("raw", msg.location),
                 orientation=_q("raw", msg.orientation))
    if isinstance(msg, m.Odometry):
        return r(msg, time=_q("scalar", msg.time), pose=_q("scalar", msg.pose))
    if isinstance(msg, (m.Eff, m.GripTruth)):
        return r(msg, time=_q("scalar", msg.time))
    if isinstance(msg, m.WcStatus):  # Str_LengthVectorFromUU / Str_AngleVectorFromUU
        return r(msg, objects=tuple(r(o, size=_q("fixed4", o.size),
                                      location=_q("fixed4", o.location),
                                      rotation=_q("fixed4", o.rotation)) for o in msg.objects))
    if isinstance(msg, m.ContactReport):
        return r(msg, time=_q("scalar", msg.time), pairs=tuple(
            r(p, first=_q("scalar", p.first), last=_q("scalar", p.last),
              depth=_q("scalar", p.depth)) for p in msg.pairs))
    return msg  # no numbers printed in a style


@pytest.mark.parametrize("kind", sorted(S.UDK_ANY))
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_udk_style_reads_back_each_number_as_its_field_prints_it(kind: str,
                                                                data: st.DataObject) -> None:
    msg = data.draw(S.UDK_ANY[kind])
    assert parse_line(format_message(msg, UDK)) == udk_quantized(msg)


def test_floatstring_fields_are_not_a_fixpoint_as_in_udk() -> None:
    assert udk_float_string(3.807, 3) == "3.806"  # float32(3.807) = 3.80699992...
    assert udk_float_string(-1.005, 3) == "-1.004"  # the KR60 link-3 offset in KR60.xml


# ------------------------------------------------------------------------------ garbage in


def check_line(text: str) -> m.Message | None:
    """Parse one line as a server or client would; the parsed message must be re-sendable."""
    try:
        msg = parse_line(text)
    except ProtocolError as exc:
        assert exc.line == text.rstrip("\r\n")
        assert 0 <= exc.position <= len(exc.line)
        return None
    assert isinstance(msg, MESSAGE_TYPES)
    if "\r" in text.rstrip("\r\n") or "\n" in text.rstrip("\r\n"):
        return msg  # not one wire line: a formatted copy would be split in two
    again = parse_line(format_message(msg, FULL))
    assert parse_line(format_message(again, FULL)) == again
    assert type(again) is type(msg)
    return msg


def feed(raw: bytes) -> None:
    """The parser fed like client.py and sim/server.py feed it: UTF-8 with replacement, whole
    and cut at every CR or LF."""
    text = raw.decode("utf-8", "replace")
    check_line(text)
    for piece in re.split("[\r\n]", text):
        if piece.strip():
            check_line(piece)


def _seed_lines() -> list[bytes]:
    lines = sorted(p.read_bytes() for p in CORPUS.iterdir() if p.is_file())
    assert len(lines) >= 50, f"the seed corpus {CORPUS} is missing"
    return lines


SEED_LINES = _seed_lines()
HEADS = [b"NFO", b"INIT", b"GETCONF", b"GETGEO", b"ACT", b"SET", b"DRIVE", b"CONF", b"GEO",
         b"ASTA", b"STA", b"SEN", b"EFF", b"GETSTARTPOSES", b"asta", b"Geo", b"MISSTA", b""]
FRAGMENTS = [
    b"{", b"}", b" ", b",", b"-", b".", b"e", b"E+", b"nan", b"-inf", b"Infinity", b"1e400",
    b"1e-400", b"0x1", b"1_0", b"\r", b"\n", b"\t", b"\x00", b"\xff", b"\xc3", "é".encode(),
    "\u2028".encode(), "\u0661".encode(), "\x85".encode(), b"9" * 40, b"9" * 4400,
    b"{Link 1}", b"{Value 2}", b"{Name x}", b"{Type Actuator}", b"{Parent 0}", b"{Tip 1,2,3}",
    b"{Location 1,2,3}", b"{Orientation 1,2}", b"{StartPoses 2}", b"{}", b"{ }", b"{On}",
    b"{Battery 1e308}", b"{Battery nan}", b"{MountLink 1.5}", b"{Time -0}", b"}{", b"{{",
]
NUMBERS = [b"0", b"-0", b"1e400", b"nan", b"inf", b"-1e-320", b"12345678901234567890", b"1,2",
           b"", b"x", b"\xd9\xa1", b"1_000", b"0.1.2", b"+3", b"9" * 4400]


def mutate(line: bytes, rng: random.Random) -> bytes:
    """A real line with 1-6 random edits that target the grammar's corners."""
    out = bytearray(line)
    for _ in range(rng.randint(1, 6)):
        op = rng.randrange(7)
        at = rng.randint(0, len(out))
        if op == 0:  # insert a significant fragment
            out[at:at] = rng.choice(FRAGMENTS)
        elif op == 1:  # delete a slice
            del out[at:at + rng.randint(1, 12)]
        elif op == 2:  # duplicate a slice elsewhere
            piece = out[at:at + rng.randint(1, 40)]
            where = rng.randint(0, len(out))
            out[where:where] = piece
        elif op == 3:  # overwrite a byte
            if at < len(out):
                out[at] = rng.randrange(256)
        elif op == 4:  # another command word
            out[: max(out.find(b"{"), 0)] = rng.choice(HEADS) + b" "
        elif op == 5:  # a weird number in place of a real one
            spots = [mt.span() for mt in re.finditer(rb"-?\d+(\.\d+)?", bytes(out))]
            if spots:
                a, b = rng.choice(spots)
                out[a:b] = rng.choice(NUMBERS)
        else:  # truncate
            del out[at:]
    return bytes(out)


def _random_text(rng: random.Random) -> bytes:
    """Text mixing the grammar's characters, ASCII and any other code point, as UTF-8."""
    chars = []
    for _ in range(rng.randint(0, 120)):
        pick = rng.random()
        if pick < 0.3:
            chars.append(rng.choice("{}{} ,.-e0123456789\r\n\t"))
        elif pick < 0.8:
            chars.append(chr(rng.randint(32, 126)))
        else:
            code = rng.randint(0, 0x10FFFF)
            chars.append(chr(code) if not 0xD800 <= code <= 0xDFFF else "\ufffd")
    return "".join(chars).encode("utf-8")


def case_from_seed(seed: int) -> bytes:
    """One garbage line, built from a 64-bit seed: random bytes (1/6), random text (1/6), a
    string of grammar fragments (1/6) or a mutated real line (1/2)."""
    rng = random.Random(seed)
    kind = rng.randrange(6)
    if kind == 0:
        return rng.randbytes(rng.randint(0, 200))
    if kind == 1:
        return _random_text(rng)
    if kind == 2:
        return b"".join(rng.choice(FRAGMENTS) for _ in range(rng.randint(0, 20)))
    return mutate(rng.choice(SEED_LINES), rng)


@st.composite
def mutated_lines(draw: st.DrawFn) -> bytes:
    """A seed-corpus line mutated by :func:`mutate` (hypothesis picks the line and the seed)."""
    line = draw(st.sampled_from(SEED_LINES))
    return mutate(line, random.Random(draw(st.integers(0, 2**64 - 1))))


def test_every_seed_line_parses_and_is_resendable() -> None:
    for raw in SEED_LINES:
        assert check_line(raw.decode()) is not None, raw


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=300))
def test_random_bytes_parse_or_raise_protocol_error(raw: bytes) -> None:
    feed(raw)


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=200))
def test_random_text_parses_or_raises_protocol_error(text: str) -> None:
    check_line(text)


@settings(max_examples=400, deadline=None)
@given(mutated_lines())
def test_mutated_real_lines_parse_or_raise_protocol_error(raw: bytes) -> None:
    feed(raw)


SLOW_CASES = 100_000


@pytest.mark.slow
def test_a_hundred_thousand_garbage_lines_parse_or_raise_protocol_error() -> None:
    # One draw per case (a seed; case_from_seed builds the line): hypothesis's own cost per
    # example (about 1 ms) is 20x that of parsing a line, and richer draws would triple it.
    count = 0

    @settings(max_examples=SLOW_CASES, deadline=None, database=None,
              phases=[Phase.generate, Phase.shrink], suppress_health_check=list(HealthCheck))
    @given(st.integers(0, 2**64 - 1))
    def run(seed: int) -> None:
        nonlocal count
        count += 1
        feed(case_from_seed(seed))

    wall, cpu = time.perf_counter(), time.process_time()
    run()
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    assert count >= SLOW_CASES, f"hypothesis ran only {count} cases"
    print(f"{count} garbage lines in {wall:.1f} s ({cpu:.1f} s CPU)")


# ------------------------------------------------------------------------------ regressions


@pytest.mark.parametrize("battery", ["inf", "nan", "1e400", "-Infinity"])
def test_a_non_finite_battery_is_a_protocol_error(battery: str) -> None:
    # Was OverflowError / ValueError from int(float(...)), which escaped the client's reader.
    line = f"STA {{Time 1.5}} {{Battery {battery}}} {{Type StaticPlatform}}"
    with pytest.raises(ProtocolError) as info:
        parse_line(line)
    assert info.value.position == line.index("{Battery")
    assert "finite number in {Battery" in info.value.reason


def test_an_integer_battery_keeps_every_digit() -> None:
    # Was read through float64: 2**53 + 1 came back as 2**53.
    msg = parse_line("STA {Time 1} {Battery 9007199254740993}")
    assert isinstance(msg, m.Sta) and msg.battery == 9007199254740993
    assert parse_line("STA {Time 1} {Battery 99.9}") == m.Sta(1.0, 99)


@pytest.mark.parametrize(("line", "key"), [
    ("ASTA {Time nan} {Name KR60Arm}", "Time"),
    ("ASTA {Time 1} {Name KR60Arm} {Link 1} {Value inf}", "Value"),
    ("ACT {Name KR60Arm} {Link 0} {Value -Infinity}", "Value"),
    ("CONF {Type Actuator} {Name a} {Link 1} {JointType Revolute} {MaxValue 1e999}", "MaxValue"),
    ("SEN {Type GroundTruth} {Name g} {Location 0,nan,0}", "Location"),
    ("NFO {StartPoses 1} {S1 0,0,0 0,0,inf}", "S1"),
])
def test_non_finite_numbers_are_refused(line: str, key: str) -> None:
    # Were accepted: Python's float() reads "nan" and "inf", and a NaN joint value or limit
    # then flows into control and the URDF.
    with pytest.raises(ProtocolError) as info:
        parse_line(line)
    assert "finite" in info.value.reason and f"{{{key} " in line[info.value.position:]


def test_udk_style_prints_numbers_beyond_float32_instead_of_failing() -> None:
    # Was OverflowError inside format_message (int() of float32 infinity).
    msg = m.Sen("GroundTruth", "g", 1.0, (1e39, 0.0, float("nan")), None)
    text = format_message(msg, UDK)
    assert "{Location inf,0.000,nan}" in text
    with pytest.raises(ProtocolError):
        parse_line(text)
