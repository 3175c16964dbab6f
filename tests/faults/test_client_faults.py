"""Every way a USARSim server can fail a client, for ``usar-arm urdf``, ``plan --execute`` and
``execute``, as a user runs them (each in a child process, against a real embedded simulator
behind a fault-injecting proxy, with ``--timeout 1``).

Each fault must give: a message on stderr that names what went wrong (and what was expected), the
exit code of its class, an exit within the timeout (plus a margin) of the fault, no partial file
(an old file is left intact), and, when it strikes during a motion, an arm that holds still.

Exit code of each class of fault (``usar-arm --help`` lists them):

=====  ========================================================================================
 69    unavailable: nobody listening; accepts and never speaks; NFO then nothing; never answers
       GETCONF/GETGEO (UDK's no-match silence); answers too slowly (1 byte per 100 ms)
 12    connection lost: closes in the middle of the GEO line
 13    invalid data from the server: a 10 MB line without a line end; garbage bytes; invalid
       UTF-8; CONF/GEO with a missing key, MinValue > MaxValue, parents that are not a chain,
       NaN or inf
  6    execution aborted, the arm holding where it is: any fault during the motion (ASTA stops,
       the server turns slow, closes, sends garbage, a 10 MB line, or NaN joint values)
=====  ========================================================================================
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from tests.faults import faults as f
from tests.faults.proxy import Fault, FaultProxy, Link, closed_port
from tests.faults.runner import Run, run_cli
from usar_arm.cli.main import main
from usar_arm.core.errors import (
    EXIT_BAD_DESCRIPTION,
    EXIT_CONNECTION_LOST,
    EXIT_EXECUTION_ABORTED,
    EXIT_OK,
    EXIT_UNAVAILABLE,
)
from usar_arm.sim.server import SimOptions, SimServer, Truth

REPO = Path(__file__).resolve().parents[2]
URDF = str(REPO / "robots" / "generated" / "KR60.urdf")
TIMEOUT_S = 1.0
MARGIN_S = 1.5
"""Allowed time between the fault and the end of main(), beyond the timeout (s): the machine is
shared, and a process winds down (closes its connection, writes its error)."""
GOAL = ["0.9", "-0.3", "0.3", "0", "0.5", "0"]
SLOWLY = ["--speed-scale", "0.3"]  # a 2 s motion, so that faults strike in the middle of it
LENIENT = ["--max-tracking-error", "0.5"]
"""On a machine loaded by other work the simulator can fall behind the wall clock, which looks
like a tracking error; these tests are about the faults, so that bound is relaxed."""
OLD = "old content\n"
STILL_RAD = 2e-3
"""How far a joint may move in 0.5 s once the arm was told to hold (rad)."""


@dataclass(frozen=True)
class Case:
    """A fault, the exit code it must give, and phrases its message must contain."""

    fault: Callable[[], Fault] | None  # None: nobody listens on the port
    code: int
    says: tuple[str, ...]


DISCOVERY: dict[str, Case] = {
    "refused": Case(None, EXIT_UNAVAILABLE, ("cannot connect", "Is the simulator running?")),
    "silent": Case(f.Silent, EXIT_UNAVAILABLE, ("no NFO greeting within 1 s", "has sent nothing")),
    "nfo-then-nothing": Case(f.NfoThenNothing, EXIT_UNAVAILABLE, (
        "no reply to `GETSTARTPOSES` within 1 s", "has sent nothing at all")),
    "no-conf-geo": Case(f.NoConfGeo, EXIT_UNAVAILABLE, (
        "no reply to `GETCONF {Type Robot}` within 1 s",
        "USARSim sends nothing when no component matches", "Actuator KR60Arm")),
    "close-mid-geo": Case(f.CloseMidGeo, EXIT_CONNECTION_LOST, (
        "closed the connection while waiting for the reply to `GETGEO {Type Actuator} "
        "{Name KR60Arm}`", "in the middle of a line")),
    "10mb-line": Case(f.LongLine, EXIT_BAD_DESCRIPTION, (
        "the reply to `GETCONF {Type Actuator} {Name KR60Arm}` is not USARSim",
        "longer than 65536 bytes without a line end")),
    "garbage": Case(f.Garbage, EXIT_BAD_DESCRIPTION, (
        "the reply to `GETCONF {Type Actuator} {Name KR60Arm}` is not USARSim",
        "is not UTF-8 text")),
    "invalid-utf8": Case(f.InvalidUtf8, EXIT_BAD_DESCRIPTION, (
        "byte 0xff at offset 31 is not UTF-8 text", "{Name KR60")),
    "conf-missing-minvalue": Case(
        lambda: f.Rewrite("conf-missing-minvalue", "CONF", r"\{MinValue -2\.0940\} ", ""),
        EXIT_BAD_DESCRIPTION, ("actuator KR60Arm", "link 3: CONF has no MinValue")),
    "geo-missing-parent": Case(
        lambda: f.Rewrite("geo-missing-parent", "GEO", r"\{Link 3\} \{Parent 2\} ", "{Link 3} "),
        EXIT_BAD_DESCRIPTION, ("`GETGEO {Type Actuator} {Name KR60Arm}` is not USARSim",
                               "GEO link 3 has no {Parent ..}")),
    "min-above-max": Case(
        lambda: f.Rewrite("min-above-max", "CONF", r"\{MinValue -2\.3560\} \{MaxValue 0\.6100\}",
                          "{MinValue 0.6100} {MaxValue -2.3560}"),
        EXIT_BAD_DESCRIPTION, ("link 2: MinValue 0.61 is not below MaxValue -2.356",)),
    "parents-not-a-chain": Case(
        lambda: f.Rewrite("parents-not-a-chain", "GEO", r"\{Link 4\} \{Parent 3\}",
                          "{Link 4} {Parent 2}"),
        EXIT_BAD_DESCRIPTION, ("do not form a serial chain", "link 2 has several children")),
    "nan": Case(
        lambda: f.Rewrite("nan", "GEO", r"\{Location 0\.491,0\.162,-0\.169\}",
                          "{Location 0.491,nan,-0.169}"),
        EXIT_BAD_DESCRIPTION, ("finite", "0.491,nan,-0.169")),
    "inf": Case(
        lambda: f.Rewrite("inf", "CONF", r"\{MinValue -3\.1400\} \{MaxValue 3\.1400\}",
                          "{MinValue -inf} {MaxValue inf}"),
        EXIT_BAD_DESCRIPTION, ("finite", "-inf")),
    "slow": Case(f.SlowServer, EXIT_UNAVAILABLE, ("no NFO greeting within 1 s",
                                                  "answering too slowly")),
}

MOTION: dict[str, Case] = {
    "asta-stops": Case(f.AstaStops, EXIT_EXECUTION_ABORTED, ("no ASTA feedback for",)),
    "slow-mid-motion": Case(f.SlowMidMotion, EXIT_EXECUTION_ABORTED, ("no ASTA feedback for",)),
    "close-mid-motion": Case(f.CloseMidMotion, EXIT_EXECUTION_ABORTED, (
        "the connection dropped",)),
    "garbage-mid-motion": Case(f.GarbageMidMotion, EXIT_EXECUTION_ABORTED, (
        "not USARSim", "is not UTF-8 text")),
    "10mb-line-mid-motion": Case(f.LongLineMidMotion, EXIT_EXECUTION_ABORTED, (
        "not USARSim", "longer than 65536 bytes")),
    "nan-asta": Case(f.NanAsta, EXIT_EXECUTION_ABORTED, ("finite",)),
}


# ------------------------------------------------------------------------------ set-up


@pytest.fixture(scope="module")
def trajectory(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 2 s PTP from home, planned offline (the simulator spawns the arm at home)."""
    path = tmp_path_factory.mktemp("plans") / "ptp.json"
    assert main(["plan", "--urdf", URDF, "--joints", *GOAL, *SLOWLY, "--out", str(path),
                 "-q"]) == EXIT_OK
    return path


@pytest.fixture
def sim() -> Iterator[SimServer]:
    """A fresh simulator for each case (robots from lingering connections stay apart)."""
    server = SimServer(SimOptions(port=0))
    server.start()
    yield server
    server.stop()


def _argv(command: str, tmp: Path, trajectory: Path) -> list[str]:
    """The command line, and the old files it must leave intact."""
    if command == "urdf":
        (tmp / "out").mkdir()
        (tmp / "out" / "KR60.urdf").write_text(OLD)
        return ["urdf", "--out-dir", str(tmp / "out"), "--acm-samples", "50", "--no-calibrate"]
    if command == "plan":
        (tmp / "out").mkdir()
        (tmp / "out" / "traj.json").write_text(OLD)
        return ["plan", "--joints", *GOAL, *SLOWLY, "--execute", *LENIENT, "--out",
                str(tmp / "out" / "traj.json"), "--bag", str(tmp / "out" / "run.bag")]
    return ["execute", str(trajectory), *LENIENT, "--out", str(tmp / "out" / "ran.json")]


def _files_left(tmp: Path) -> dict[str, str]:
    folder = tmp / "out"
    if not folder.exists():
        return {}
    return {str(p.relative_to(folder)): p.read_text() if p.is_file() else "<dir>"
            for p in sorted(folder.rglob("*"))}


def _expected_files(command: str) -> dict[str, str]:
    return {"urdf": {"KR60.urdf": OLD}, "plan": {"traj.json": OLD}, "execute": {}}[command]


def _check(run: Run, case: Case, fault_at: float | None, tmp: Path, command: str,
           record: Callable[[str, object], None]) -> None:
    """The checks every fault must pass (the times go to the JUnit report's properties)."""
    struck = max(fault_at or run.began, run.began)
    latency = run.ended - struck
    record("exit_code", run.code)
    record("main_s", round(run.seconds, 3))
    record("fault_to_exit_s", round(latency, 3))
    assert run.code == case.code, f"exit {run.code}, expected {case.code}; stderr:\n{run.stderr}"
    message = run.stderr
    assert "usar-arm: error:" in message and "Traceback" not in message, message
    for phrase in case.says:
        assert phrase in message, f"'{phrase}' not in stderr:\n{message}"
    assert latency <= TIMEOUT_S + MARGIN_S, f"{latency:.2f} s from the fault to the exit"
    assert run.exited - run.ended < 3.0, "the process took too long to wind down"
    assert _files_left(tmp) == _expected_files(command)


def _run(command: str, port: int, tmp: Path, trajectory: Path) -> Run:
    argv = [*_argv(command, tmp, trajectory),
            "--host", "127.0.0.1", "--port", str(port), "--timeout", str(TIMEOUT_S)]
    return run_cli(argv, tmp / "io", hard_timeout=60)


# ------------------------------------------------------------------------------ discovery faults


@pytest.mark.parametrize("command", ["urdf", "plan", "execute"])
@pytest.mark.parametrize("name", list(DISCOVERY))
def test_a_server_fault_while_learning_the_arm(
        name: str, command: str, sim: SimServer, trajectory: Path, tmp_path: Path,
        record_property: Callable[[str, object], None]) -> None:
    case = DISCOVERY[name]
    if case.fault is None:
        run = _run(command, closed_port(), tmp_path, trajectory)
        _check(run, case, None, tmp_path, command, record_property)
        return
    assert sim.port is not None
    with FaultProxy(sim.port, case.fault()) as proxy:
        run = _run(command, proxy.port, tmp_path, trajectory)
        assert proxy.fault_at is not None, "the fault never struck"
        _check(run, case, proxy.fault_at, tmp_path, command, record_property)


# ------------------------------------------------------------------------------ motion faults


class JointRecorder:
    """Samples the joints of the robot that a proxied connection owns, from the physics, with
    the wall-clock (time.monotonic) and the simulated time of each sample."""

    def __init__(self, sim: SimServer, proxy: FaultProxy):
        self.sim = sim
        self.proxy = proxy
        self.samples: list[tuple[float, float, np.ndarray]] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def _truth(self) -> Truth | None:
        """The simulator's state of the robot of the proxied connection, if it has one."""
        for port in {lk.upstream_port for lk in self.proxy.links} - {None}:
            truth = self.sim.truth(port)
            if truth is not None:
                return truth
        return None

    def _loop(self) -> None:
        while not self._stop.wait(0.02):
            truth = self._truth()
            if truth is not None:
                self.samples.append((time.monotonic(), truth.sim_time,
                                     np.array(truth.joints["KR60Arm"])))

    def at(self, when: float) -> tuple[float, np.ndarray]:
        """The simulated time and the joints of the last sample before wall time ``when``."""
        before = [(s, q) for t, s, q in self.samples if t <= when]
        assert before, "no joint sample before that time"
        return before[-1]

    def after_sim(self, sim_time: float, timeout: float = 10.0) -> np.ndarray:
        """The joints of the first sample at simulated time ``sim_time`` or later (waits for
        it: a busy machine slows the simulation down)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            later = [q for _, s, q in self.samples if s >= sim_time]
            if later:
                return later[0]
            time.sleep(0.05)
        raise AssertionError(f"the simulation did not reach t = {sim_time:.2f} s")

    def robot_exists(self) -> bool:
        return self._truth() is not None

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2)


def _holds_still(recorder: JointRecorder, link: Link,
                 record: Callable[[str, object], None]) -> None:
    """After the abort the arm comes to rest where the client told it to hold (the last ACT),
    short of the goal, and not back where stale feedback had it: the hold is no further back
    along the motion than where the arm was when the fault struck. Times are simulated time
    from the hold: 0.5 s to come to rest, then still for 0.5 s."""
    assert link.last_act_at is not None and link.last_act is not None
    assert link.fault_at is not None
    held_at, _ = recorder.at(link.last_act_at)
    rested = recorder.after_sim(held_at + 0.5)
    final = recorder.after_sim(held_at + 1.0)
    moved = float(np.max(np.abs(final - rested)))
    record("moved_in_0.5s_after_hold_rad", round(moved, 5))
    assert moved < STILL_RAD, f"the arm still moves {moved:.4f} rad per 0.5 s after the abort"
    goal = np.array([float(v) for v in GOAL])
    assert np.max(np.abs(final - goal)) > 0.1, "the motion was not stopped: the arm is at the goal"
    hold = np.array(link.last_act)
    off = float(np.max(np.abs(final - hold)))
    record("rest_vs_hold_rad", round(off, 4))
    assert off < 0.02, f"the arm rests {off:.3f} rad from the hold it was sent"
    direction = goal / np.linalg.norm(goal)  # the motion starts at home (zeros)
    ahead = float((hold - recorder.at(link.fault_at)[1]) @ direction)
    record("hold_ahead_of_fault_rad", round(ahead, 4))
    assert ahead > -0.02, f"the hold is {-ahead:.3f} rad back along the motion from the fault"


@pytest.mark.slow
@pytest.mark.parametrize("command", ["plan", "execute"])
@pytest.mark.parametrize("name", list(MOTION))
def test_a_server_fault_during_the_motion(
        name: str, command: str, trajectory: Path, tmp_path: Path,
        record_property: Callable[[str, object], None]) -> None:
    case = MOTION[name]
    assert case.fault is not None
    for attempt in (1, 2):
        folder = tmp_path / f"attempt{attempt}"
        folder.mkdir()
        with SimServer(SimOptions(port=0)) as sim, \
                FaultProxy(sim.port or 0, case.fault(), linger=True) as proxy:
            recorder = JointRecorder(sim, proxy)
            try:
                run = _run(command, proxy.port, folder, trajectory)
                if proxy.fault_at is None and attempt == 1:
                    # The shared machine starved the simulator before the fault could strike
                    # (the run stopped on late feedback, a genuine abort): once more, said aloud.
                    print(f"\n{name}/{command}: the fault did not fire on attempt 1 "
                          f"(stderr: {run.stderr.strip()[-200:]}); retrying")
                    continue
                record_property("attempts", attempt)
                assert proxy.fault_at is not None, f"the fault never fired:\n{run.stderr}"
                link = proxy.links[-1]
                assert link.motion_at is not None, f"the motion never started:\n{run.stderr}"
                _check(run, case, proxy.fault_at, folder, command, record_property)
                assert "execution aborted" in run.stderr and "told to hold" in run.stderr
                if name == "close-mid-motion":  # nothing left to hold: the server destroys it
                    end = time.monotonic() + 5
                    while recorder.robot_exists() and time.monotonic() < end:
                        time.sleep(0.05)
                    assert not recorder.robot_exists(), "the server keeps a lost client's robot"
                else:
                    _holds_still(recorder, link, record_property)
                return
            finally:
                recorder.stop()


def test_the_installed_command_reports_a_silent_server_the_same_way(
        sim: SimServer, tmp_path: Path) -> None:
    """The console script itself (not a fork of the test process): exit code, message, time."""
    import subprocess
    import sys

    assert sim.port is not None
    with FaultProxy(sim.port, f.Silent()) as proxy:
        begin = time.monotonic()
        done = subprocess.run(
            [str(Path(sys.executable).parent / "usar-arm"), "urdf", "--host", "127.0.0.1",
             "--port", str(proxy.port), "--timeout", "1", "--out-dir", str(tmp_path / "out")],
            capture_output=True, text=True, timeout=60)
        seconds = time.monotonic() - begin
    assert done.returncode == EXIT_UNAVAILABLE, done.stderr
    assert "no NFO greeting within 1 s" in done.stderr
    assert seconds < 15  # imports take a few seconds on a shared machine
    assert not (tmp_path / "out").exists()


def test_the_mapping_in_this_module_matches_the_help(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["--help"])
    text = capsys.readouterr().out
    for code in {c.code for c in (*DISCOVERY.values(), *MOTION.values())}:
        assert f"\n  {code} " in text, f"exit code {code} is not in usar-arm --help"
