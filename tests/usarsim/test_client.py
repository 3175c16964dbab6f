"""The wire client: framing, timeouts on every wait, and failures named clearly."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable

import pytest

from tests.usarsim.fake_server import FakeServer, read_line
from usar_arm.core.errors import (
    EXIT_BAD_DESCRIPTION,
    ConnectionFailedError,
    ConnectionLostError,
    ProtocolError,
    ResponseTimeoutError,
    UnknownComponentError,
)
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import BadLine, LineSplitter, Received, UsarClient
from usar_arm.usarsim.codec import MAX_LINE_BYTES

NFO = b"NFO {Gametype BotDeathMatch} {Level test} {TimeLimit 0}\r\n"


def test_lines_are_framed_across_partial_reads_and_mixed_terminators() -> None:
    def script(conn: socket.socket) -> None:
        conn.sendall(NFO[:10])
        time.sleep(0.05)
        conn.sendall(NFO[10:])
        # Several lines in one write, every terminator kind, and a line split mid-block.
        conn.sendall(b"STA {Time 0.1} {Battery 99999} {Type StaticPlatform}\n"
                     b"ASTA {Time 0.1} {Name Arm} {Link 1} {Value 0.5}\r"
                     b"SEN {Time 0.1} {Type GroundTruth} {Name GT} {Location 1,2,3} {Orient")
        time.sleep(0.05)
        conn.sendall(b"ation 0,0,0}\r\n\r\nASTA {Time 0.2} {Name Arm} {Link 1} {Value 0.6}\r\n")
        time.sleep(1.0)

    seen: list[Received] = []
    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=2.0) as client:
        client.subscribe(seen.append)
        asta = client.wait_asta("Arm", after_time=0.15)
        assert asta.values == ((1, 0.6),)
        sen = client.latest_sen("GT")
        assert sen is not None and sen.location == (1.0, 2.0, 3.0)
        assert client.game_info == m.GameInfo("BotDeathMatch", "test", 0.0)
    kinds = [type(r.message).__name__ for r in seen]
    assert kinds.count("Asta") >= 1 and "Sen" in kinds


def test_each_received_line_carries_the_precision_it_was_printed_with() -> None:
    """Callers learn a reading's printed step from the reading, not by re-reading its text."""
    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        conn.sendall(b"SEN {Time 0.10} {Type GroundTruth} {Name Tip} {Location 1.250,2.000,-0.5}"
                     b" {Orientation 0.01,3.14,0.00}\r\n"
                     b"ASTA {Time 0.1} {Name Arm} {Link 0} {Value 1.25e-07} {Link 1} {Value 2}\r\n")
        time.sleep(1.0)

    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=2.0) as client:
        sen = client.wait_stream("SEN", "Tip")
        asta = client.wait_stream("ASTA", "Arm")
    assert isinstance(sen.message, m.Sen)
    assert sen.step("Location") == pytest.approx(0.001)
    assert sen.step("orientation") == pytest.approx(0.01)
    assert sen.step("Time") == pytest.approx(0.01)
    assert sen.step("Missing") == 0.0
    assert asta.step("Value") == 0.0  # exponent notation: a full-precision server


def test_a_getconf_that_matches_nothing_fails_after_the_timeout_naming_known_components() -> None:
    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        conn.sendall(b"ASTA {Time 0.1} {Name KR60Arm} {Link 1} {Value 0}\r\n"
                     b"SEN {Time 0.1} {Type GroundTruth} {Name GroundTruth} {Location 0,0,0}\r\n")
        read_line(conn)  # the GETCONF: UDK answers nothing
        time.sleep(3)

    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=0.5) as client:
        client.wait_asta("KR60Arm")
        client.wait_sen("GroundTruth")
        start = time.monotonic()
        with pytest.raises(UnknownComponentError) as info:
            client.get_conf("Actuator", "KR61Arm")
        assert time.monotonic() - start < 1.5
    text = str(info.value)
    assert "GETCONF {Type Actuator} {Name KR61Arm}" in text
    assert "Actuator KR60Arm" in text and "GroundTruth GroundTruth" in text


def test_a_server_closing_mid_reply_is_reported_promptly() -> None:
    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        read_line(conn)
        conn.sendall(b"GEO {Type Actuator} {Name KR60Arm} {Location 0,0,0} {Link 1} {Par")

    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=5.0) as client:
        start = time.monotonic()
        with pytest.raises(ConnectionLostError) as info:
            client.get_geo("Actuator", "KR60Arm")
        assert time.monotonic() - start < 2.0
    assert "unterminated" in str(info.value)


def test_a_reply_that_came_just_before_the_close_still_answers_the_request() -> None:
    """A server that answers and hangs up at once: the answer wins over the close, however the
    threads interleave. The client's send is made to wait until the close has been seen, the
    interleaving that lost the reply once in CI."""
    geo = b"GEO {Type Actuator} {Name KR60Arm} {Location 0,0,0} {Link 1} {ParentLink 0}" \
          b" {Location 0,0,0} {Orientation 0,0,0}\r\n"

    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        read_line(conn)
        conn.sendall(geo)

    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=3.0) as client:
        plain_send = client.send

        def send_then_see_the_close(msg: m.Message) -> None:
            plain_send(msg)
            deadline = time.monotonic() + 3.0
            while client.closed_reason is None and time.monotonic() < deadline:
                time.sleep(0.005)
            assert client.closed_reason is not None, "the fake server did not hang up"

        client.send = send_then_see_the_close  # type: ignore[method-assign]
        reply = client.get_geo("Actuator", "KR60Arm", timeout=3.0)
    assert reply.items[0].name == "KR60Arm"


def test_connection_refused_names_the_address_and_how_to_start_a_simulator() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(ConnectionFailedError) as info:
        UsarClient(port=port, connect_timeout=1.0).connect()
    assert f"127.0.0.1:{port}" in str(info.value) and "usar-arm sim" in str(info.value)


def test_a_server_that_never_greets_times_out() -> None:
    with FakeServer(lambda conn: time.sleep(3)) as srv:
        start = time.monotonic()
        with pytest.raises(ResponseTimeoutError) as info:
            UsarClient(port=srv.port, connect_timeout=0.5).connect()
        assert time.monotonic() - start < 1.5
    assert "NFO" in str(info.value)


def test_a_late_reply_is_not_mistaken_for_the_answer_to_the_next_request() -> None:
    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        read_line(conn)  # first GETCONF: answered too late
        time.sleep(0.8)
        conn.sendall(b"CONF {Type Actuator} {Name Old} {Link 1} {JointType Revolute}\r\n")
        read_line(conn)  # second GETCONF
        conn.sendall(b"CONF {Type Actuator} {Name New} {Link 1} {JointType Prismatic}\r\n")
        time.sleep(1)

    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=0.4) as client:
        with pytest.raises(UnknownComponentError):
            client.get_conf("Actuator", "Old")
        time.sleep(0.6)
        conf = client.get_conf("Actuator", "New", timeout=2.0)
    assert isinstance(conf, m.Conf) and conf.items[0].name == "New"


def _wait_until(condition: Callable[[], bool], timeout: float = 3.0) -> None:
    end = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < end, "condition not met in time"
        time.sleep(0.01)


def test_malformed_status_lines_and_overlong_lines_are_counted_skipped_and_named() -> None:
    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        conn.sendall(b"ASTA {Time 0.1 {Name broken}\r\n")
        # Past the 64 KiB limit the rest of a line is skipped, even text that looks like a line.
        conn.sendall(b"X" * 70000 + b"ASTA {Time 0.2} {Name Arm} {Link 1} {Value 9}\r\n")
        conn.sendall(b"ASTA {Time 0.3} {Name Arm} {Link 1} {Value 1.5}\r\n")
        time.sleep(1)

    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=2.0) as client:
        _wait_until(lambda: client.latest_asta("Arm") is not None)
        assert client.wait_asta("Arm").values == ((1, 1.5),)
        assert client.bad_line_count == 2
        first, second = client.bad_lines
        assert first.head == "ASTA" and "'{' inside a block" in first.error.reason
        assert second.head == "" and "longer than 65536 bytes" in second.error.reason


def test_the_line_buffer_stays_bounded_on_ten_megabytes_without_a_line_end() -> None:
    splitter = LineSplitter()
    found = []
    for _ in range(160):  # 10 MiB in 64 KiB reads
        found += splitter.feed(b"y" * 65536)
        assert splitter.partial <= MAX_LINE_BYTES
    assert len(found) == 1 and isinstance(found[0], BadLine)
    assert splitter.feed(b"yyy\nSTA {Time 1}\r\n") == [b"STA {Time 1}"]


def _reply_with(reply: bytes) -> Callable[[socket.socket], None]:
    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        read_line(conn)
        conn.sendall(reply)
        time.sleep(3)
    return script


@pytest.mark.parametrize(("reply", "reason"), [
    (bytes(range(1, 10)) + b"\xff\xfe garbage\r\n", "is not UTF-8 text"),
    (b"CONF {Type Actuator} {Name A\x01} {Link 1}\r\n", "control character 0x01"),
    (b"CONF {Type Actuator} {Name A} {Link 1} {MinValue nan}\r\n", "finite"),
    (b"\x1b[2J%%%%\r\n", "control character 0x1b"),
    (b"%%%% !!!\r\n", "single word"),
    (b"CONF {Type Actuator} {Name " + b"z" * 10_000_000, "longer than 65536 bytes"),
])
def test_a_reply_that_is_not_usarsim_fails_the_request_at_once(reply: bytes, reason: str) -> None:
    with FakeServer(_reply_with(reply)) as srv, UsarClient(port=srv.port, timeout=5.0) as client:
        start = time.monotonic()
        with pytest.raises(ProtocolError) as info:
            client.get_conf("Actuator", "A")
        assert time.monotonic() - start < 2.0  # not the 5 s timeout
    assert "the reply to `GETCONF {Type Actuator} {Name A}` is not USARSim" in str(info.value)
    assert reason in str(info.value)
    assert info.value.exit_code == EXIT_BAD_DESCRIPTION


def test_a_malformed_asta_fails_a_wait_for_asta_at_once() -> None:
    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        time.sleep(0.3)
        conn.sendall(b"ASTA {Time 0.1} {Name Arm} {Link 1} {Value inf}\r\n")
        time.sleep(3)

    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=5.0) as client:
        start = time.monotonic()
        with pytest.raises(ProtocolError, match="while waiting for ASTA from actuator Arm"):
            client.wait_asta("Arm")
        assert time.monotonic() - start < 2.0


def test_the_greeting_wait_follows_the_timeout_and_names_silence_slowness_and_garbage() -> None:
    with FakeServer(lambda conn: time.sleep(3)) as srv:
        start = time.monotonic()
        with pytest.raises(ResponseTimeoutError, match="has sent nothing"):
            UsarClient(port=srv.port, timeout=0.5).connect()  # no connect_timeout given
        assert time.monotonic() - start < 1.0

    def slow(conn: socket.socket) -> None:
        for byte in NFO:
            conn.sendall(bytes([byte]))
            time.sleep(0.1)

    with FakeServer(slow) as srv, pytest.raises(ResponseTimeoutError, match="too slowly"):
        UsarClient(port=srv.port, timeout=0.5).connect()

    def http(conn: socket.socket) -> None:
        conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n")
        time.sleep(3)

    with FakeServer(http) as srv:
        start = time.monotonic()
        with pytest.raises(ProtocolError, match="instead of the NFO greeting"):
            UsarClient(port=srv.port, timeout=2.0).connect()
        assert time.monotonic() - start < 1.0


def test_a_reply_too_slow_to_finish_is_called_slow_not_missing() -> None:
    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        read_line(conn)
        for byte in b"CONF {Type Actuator} {Name A} {Link 1}\r\n":
            conn.sendall(bytes([byte]))
            time.sleep(0.1)

    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=0.5) as client:
        with pytest.raises(ResponseTimeoutError) as info:
            client.get_conf("Actuator", "A")
    assert not isinstance(info.value, UnknownComponentError)
    assert "answering too slowly" in str(info.value) and "unfinished" in str(info.value)


def test_act_sends_zero_based_links_in_one_line() -> None:
    got: list[str] = []
    done = threading.Event()

    def script(conn: socket.socket) -> None:
        conn.sendall(NFO)
        got.append(read_line(conn))
        got.append(read_line(conn))
        done.set()

    with FakeServer(script) as srv, UsarClient(port=srv.port) as client:
        client.act("KR60Arm", [0.1, -0.25, 3.0])
        client.act("KR60Arm", {4: 0.5})
        assert done.wait(3)
    assert got[0] == ("ACT {Name KR60Arm} {Link 0} {Value 0.1} {Link 1} {Value -0.25} "
                      "{Link 2} {Value 3.0}")
    assert got[1] == "ACT {Name KR60Arm} {Link 4} {Value 0.5}"
