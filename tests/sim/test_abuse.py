"""Bad clients never disturb the simulator: what it refuses, how it says so, whom it keeps serving.

Malformed, oversized and binary lines, clients vanishing mid-line, a client that never reads, and a
flood of 10,000 lines/s: each is refused (or served) and counted per connection, logged without
flooding the log, and the well-behaved clients keep their 10 Hz status and quick replies.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import logging
import random
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from usar_arm.core.errors import ProtocolError
from usar_arm.sim.connection import MAX_WRITE_BUFFER, fast_act
from usar_arm.sim.robot_session import LOG_FIRST
from usar_arm.sim.server import SimServer
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.codec import MAX_LINE_BYTES, parse_line

TOOLS = Path(__file__).resolve().parents[2] / "tools"
INIT = b"INIT {ClassName USARBot.KR60} {Start RobotStart1}\r\n"


def _raw(port: int) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


def _read_until(sock: socket.socket, needle: bytes, count: int = 1, timeout: float = 5) -> bytes:
    data = b""
    deadline = time.monotonic() + timeout
    while data.count(needle) < count:
        sock.settimeout(max(0.01, deadline - time.monotonic()))
        chunk = sock.recv(65536)
        assert chunk, f"connection closed; got {data[-300:]!r}"
        data += chunk
    return data


def _connected(sim: SimServer, peer: str) -> bool:
    """Whether the simulator still has a session for the client at ``peer``."""
    return any(client.peer == peer for client in sim.clients())


def _key(sim: SimServer, peer: str) -> str:
    """The server's key of the client at ``peer`` (that of its robot too)."""
    keys = [c.key for c in sim.clients() if c.peer == peer]
    assert len(keys) == 1, f"{peer}: {keys}"
    return keys[0]


def _wait_received(sim: SimServer, peer: str, count: int, timeout: float = 5) -> None:
    """Wait until the simulator has received ``count`` bytes from the client at ``peer``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if any(c.peer == peer and c.received_bytes >= count for c in sim.clients()):
            return
        time.sleep(0.005)
    raise AssertionError(f"the simulator did not receive {count} bytes from {peer}")


def _summary(caplog: pytest.LogCaptureFixture, port: int, timeout: float = 5) -> str:
    """The server's disconnect log line for the client at local port ``port``."""
    peer = f"127.0.0.1:{port}: disconnected"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for rec in list(caplog.records):
            if rec.getMessage().startswith(peer):
                return rec.getMessage()
        time.sleep(0.02)
    raise AssertionError(f"no disconnect summary for {peer}")


def _act(rng: random.Random) -> bytes:
    pairs = " ".join(f"{{Link {rng.randint(-2, 9)}}} "
                     f"{{Value {rng.uniform(-4, 4):.{rng.randint(0, 6)}f}}}"
                     for _ in range(rng.randint(1, 7)))
    head = rng.choice(["ACT", "act", "Act"])
    return f"{head} {{Name {rng.choice(['KR60Arm', 'kr60arm', 'X'])}}} {pairs}".encode()


def test_the_act_fast_path_reads_exactly_what_the_parser_reads() -> None:
    rng = random.Random(8)
    canonical = [_act(rng) for _ in range(300)]
    odd = [b"ACT {Name KR60Arm} {Link 0} {Value nan}", b"ACT {Name KR60Arm} {Link 0} {Value inf}",
           b"ACT {Name KR60Arm} {Link 0} {Value 1e400}", b"ACT {Name KR60Arm} {Link 0} {Value x}",
           b"ACT {Name KR60Arm} {Link 00} {Value -0}", b"ACT {Name KR60Arm} {link 0} {Value 1}",
           b"ACT {Name KR60Arm}  {Link 0} {Value 1}", b"ACT {Name KR60Arm}{Link 0} {Value 1}",
           b"ACT {Name KR60Arm} {Link 0} {Value 1} {Gripper 1}", b"ACT {Link 0} {Value 1}",
           b"ACT {Name KR 60} {Link 0} {Value 1}", b"ACT {Name KR60Arm} {Link 1_0} {Value 1}",
           b"ACT {Name KR60Arm} {Link 0} {Value 1_0.5}", b"  ACT {Name a} {Link 1} {Value 2}  "]
    taken = 0
    for raw in canonical + odd:
        fast = fast_act(raw)
        try:
            slow = parse_line(raw.decode())
        except ProtocolError:
            slow = None
        if fast is not None:
            taken += 1
            assert fast == slow, raw
    assert taken >= len(canonical)  # every canonical line takes the fast path


def test_line_ends_of_any_kind_and_lines_split_anywhere_are_read_alike(sim: SimServer) -> None:
    with _raw(sim.port) as sock:
        _read_until(sock, b"NFO")
        for byte in b"GETSTARTPOSES\r":
            sock.sendall(bytes([byte]))
        sock.sendall(b"\nGETSTARTPOSES\n\n\r\nGETSTARTPOSES\r")
        sock.sendall(b"GETSTARTPOSES\r\n")
        assert _read_until(sock, b"StartPoses", 4).count(b"StartPoses") == 4


def test_junk_is_refused_counted_and_logged_a_few_times_only(
        sim: SimServer, caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="usar_arm.sim")
    with _raw(sim.port) as sock:
        port = sock.getsockname()[1]
        sock.sendall(INIT)
        _read_until(sock, b"ASTA")
        sock.sendall(b"ASTA {Time {broken}}\r\n" * 300 + b"}{\r\n" * 200)  # malformed
        sock.sendall((b"\x00\x01\xff\xfe garbage \x07\r\n") * 50)  # binary
        sock.sendall(b"FROB {Key 1}\r\n" * 40)  # unknown command
        sock.sendall(b"ACT {Name KR60Arm} {Link 9} {Value 1}\r\n" * 30)  # out of range
        sock.sendall(b"ACT {Name KR60Arm} " + b"{Link 0} {Value 0.1} " * 4000 + b"\r\n")
        for _ in range(20):  # an oversized line trickling in
            sock.sendall(b"y" * (MAX_LINE_BYTES // 10))
            time.sleep(0.002)
        sock.sendall(b" still the oversized line\r\nGETCONF {Type Robot}\r\n")
        assert b"CONF {Name" in _read_until(sock, b"CONF {Name")  # still served
        sock.sendall(b"ACT {Name KR60Arm} {Link 0} {Value 0.2}\r\n" * 10)
        time.sleep(0.2)
    summary = _summary(caplog, port)
    for part in ("malformed 500", "binary 50", "unknown command 40", "link out of range 30",
                 "oversized 2"):
        assert part in summary, summary
    # INIT, GETCONF and 10 good ACT lines served; the oversized lines count once each
    assert "634 lines, served 12, refused 622" in summary, summary
    mine = [r for r in caplog.records if f":{port}:" in r.getMessage()
            and r.levelno >= logging.WARNING]
    assert len(mine) <= 5 * LOG_FIRST, [r.getMessage()[:80] for r in mine]


def test_a_client_leaving_mid_line_loses_its_robot_and_nothing_else(
        sim: SimServer, caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="usar_arm.sim")
    left: set[str] = set()  # the server's keys of the clients that leave mid-line
    with UsarClient(port=sim.port, timeout=3) as good:
        good.spawn("USARBot.KR60", start="RobotStart1")
        good_key = _key(sim, f"127.0.0.1:{good.local_port}")
        for abort in (False, True):
            sock = _raw(sim.port)
            port = sock.getsockname()[1]
            sock.sendall(INIT)
            _read_until(sock, b"ASTA")
            left.add(_key(sim, f"127.0.0.1:{port}"))
            sock.sendall(b"GETGEO {Type Actua")
            # TCP may drop what the server has not read when a connection is reset (a reset
            # also comes from closing with unread ASTA lines): the line is mid-way once the
            # server holds all 18 bytes, and only then does the client leave.
            _wait_received(sim, f"127.0.0.1:{port}", len(INIT) + 18)
            if abort:  # RST instead of FIN
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\0\0\0\0\0\0\0")
            sock.close()
            assert "unterminated at disconnect 1" in _summary(caplog, port)
        t0 = good.wait_asta("KR60Arm").time
        assert good.wait_asta("KR60Arm", after_time=t0, timeout=2).time > t0
        assert good.get_conf("Robot").name == "KR60"
        # (robots of earlier tests' clients may still be leaving: only these are compared)
        deadline = time.monotonic() + 3
        while left & set(sim.world.robot_keys) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert not left & set(sim.world.robot_keys)
        assert good_key in sim.world.robot_keys
    assert any("left mid-line (18 bytes unterminated)" in r.getMessage() for r in caplog.records)


def test_a_client_that_never_reads_cannot_pile_up_memory_or_slow_the_others(
        sim: SimServer, caplog: pytest.LogCaptureFixture) -> None:
    """A deaf client asking for ~0.7 MB of replies per burst: the server queues at most
    MAX_WRITE_BUFFER for it (then disconnects it, logging why; or, when it has stopped reading
    the deaf client's requests, queues nothing more), and serves the others meanwhile."""
    caplog.set_level(logging.INFO, logger="usar_arm.sim")
    with UsarClient(port=sim.port, timeout=3) as good:
        good.spawn("USARBot.KR60", start="RobotStart1")
        sock = _raw(sim.port)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        sock.sendall(INIT)
        time.sleep(0.2)
        sock.settimeout(0.5)
        peer = f"127.0.0.1:{sock.getsockname()[1]}"
        most = 0
        end = time.monotonic() + 8
        while _connected(sim, peer) and time.monotonic() < end:
            with contextlib.suppress(OSError):  # blocked (timeout) or reset by the server
                sock.sendall(b"GETGEO {Type Actuator}\r\n" * 1000)  # ~0.7 MB of replies
            most = max(most, _queued(sim, peer))
            assert good.get_conf("Robot").name == "KR60"  # served meanwhile
        assert most <= MAX_WRITE_BUFFER + 1_000_000, most
        if not _connected(sim, peer):
            deadline = time.monotonic() + 5
            while not any("not reading its messages" in r.getMessage() for r in caplog.records):
                assert time.monotonic() < deadline, "disconnected without saying why"
                time.sleep(0.02)
        sock.close()
        assert good.get_conf("Robot").name == "KR60"


def _queued(sim: SimServer, peer: str) -> int:
    """Bytes the simulator holds for the client at ``peer`` (0 when it is gone)."""
    return sum(client.queued_bytes for client in sim.clients() if client.peer == peer)


def test_a_flood_of_ten_thousand_lines_a_second_leaves_the_others_their_rate(
        sim: SimServer, caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="usar_arm.sim")
    with UsarClient(port=sim.port, timeout=3) as good:
        good.spawn("USARBot.KR60", start="RobotStart1")
        flood = _raw(sim.port)
        port = flood.getsockname()[1]
        flood.sendall(INIT)
        stop = threading.Event()
        sent = [0]

        def pump() -> None:  # 100 lines every 10 ms, half valid ACT, half malformed
            batch = (b"ACT {Name KR60Arm} {Link 0} {Value 0.1}\r\n"
                     b"ACT {Name KR60Arm} {Link x} {Value 0.1}\r\n") * 50
            due = time.monotonic()
            while not stop.is_set():
                flood.sendall(batch)
                sent[0] += 100
                due += 0.01
                time.sleep(max(0.0, due - time.monotonic()))

        pumping = threading.Thread(target=pump)
        t_flood = time.monotonic()
        pumping.start()
        try:
            stamps, rtts = [], []
            t0 = good.wait_asta("KR60Arm").time
            while time.monotonic() - t_flood < 2.0:
                asta = good.wait_asta("KR60Arm", after_time=t0, timeout=2)
                stamps.append(time.monotonic())
                t0 = asta.time
                if len(stamps) % 4 == 0:
                    sent_at = time.monotonic()
                    good.get_conf("Robot")
                    rtts.append(time.monotonic() - sent_at)
        finally:
            stop.set()
            pumping.join()
            flood.close()
    rate = sent[0] / (time.monotonic() - t_flood)
    gaps = [b - a for a, b in itertools.pairwise(stamps)]
    assert rate > 5000  # the flood really flowed (>5,000 lines/s even on a busy machine)
    assert len(stamps) >= 15 and max(gaps) < 0.35, gaps
    assert max(rtts) < 0.25, rtts
    summary = _summary(caplog, port)
    counted = int(summary.split(" lines, served ")[0].rsplit(" ", 1)[1])
    assert "malformed" in summary and counted > 0.9 * sent[0] - 2000, summary


def test_the_abuse_tool_keeps_everyone_served_in_every_phase(tmp_path: Path) -> None:
    out = tmp_path / "abuse.json"
    proc = subprocess.run([sys.executable, str(TOOLS / "abuse_sim.py"), "--clients", "4",
                           "--phase-seconds", "1.5", "--midline-clients", "6",
                           "--json", str(out), "--server-log", str(tmp_path / "sim.log")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    result = json.loads(out.read_text())
    for name, phase in result["phases"].items():
        asta = phase["asta"]
        assert asta["asta_per_sim_s"]["min"] >= 9.9, (name, asta)
        assert asta["max_gap_sim_s"]["max"] < 0.11, (name, asta)
        assert asta["probe_timeouts"] == 0, (name, asta)
        for abuser in phase["abusers"]:
            seen = abuser["server"]
            assert seen is not None, (name, abuser)
            assert seen["lines"] >= 0.9 * abuser["sent_lines"] - 2000, (name, abuser)
            if abuser["kind"] == "act":
                assert seen["served"] >= 0.9 * seen["lines"], (name, abuser)
            else:
                assert seen["served"] <= 0.01 * seen["lines"] + 1, (name, abuser)
    flood = result["phases"]["flood-act"]["abusers"][0]
    assert flood["achieved_rate"] > 5000, flood
    assert all(s is not None for s in result["midline_server"])
    counts = result["server_log_counts"]
    assert counts["errors"] == 0 and counts["tracebacks"] == 0
    assert result["server_log_lines"] < 400  # 100,000 refusals do not flood the log
