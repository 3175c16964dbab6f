"""64 clients at once: everyone keeps a 10 Hz status stream, nobody slows anybody, memory is flat.

These run ``tools/load_sim.py`` against ``usar-arm sim`` in its own process. On a shared machine
the simulator may not get a whole CPU; the rates measured in wall time are then only required
when the simulator's thread waited for a CPU less than :data:`BUSY_WAIT_PERCENT` of the time
(the figures are in the JSON either way). Rates in simulated time are required always.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

TOOLS = Path(__file__).resolve().parents[2] / "tools"
BUSY_WAIT_PERCENT = 15.0
"""Above this share of time waiting for a CPU the machine, not the simulator, sets the pace."""


def run_load(tmp_path: Path, *args: str, timeout: float) -> dict[str, Any]:
    out = tmp_path / "load.json"
    proc = subprocess.run([sys.executable, str(TOOLS / "load_sim.py"), *args, "--json", str(out),
                           "--server-log", str(tmp_path / "sim.log")],
                          capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stderr[-3000:]
    result: dict[str, Any] = json.loads(out.read_text())
    sys.stderr.write(proc.stderr)  # the summary, for -s and for the report
    return result


def check_rates(result: dict[str, Any], clients: int, wall_rate: bool = True) -> None:
    asta, server = result["asta"], result["server"]
    assert not asta["lost"] and result["server_alive"]
    assert asta["asta_per_sim_s"]["n"] == clients
    assert asta["asta_per_sim_s"]["min"] >= 9.95  # exactly 10 per simulated second
    assert asta["max_gap_sim_s"]["max"] < 0.11
    assert asta["probe_timeouts"] == 0
    # nobody is served worse than the others
    wall = asta["asta_per_wall_s"]
    assert wall["min"] >= 0.95 * wall["max"], wall
    if wall_rate and server["runqueue_wait_percent"] < BUSY_WAIT_PERCENT:
        assert wall["min"] >= 9.5, (wall, server)
        assert result["server_log_counts"]["cannot_keep_up"] == 0
    assert result["server_log_counts"]["errors"] == 0
    assert result["server_log_counts"]["tracebacks"] == 0


def test_eight_clients_at_100_hz_get_10_hz_status(tmp_path: Path) -> None:
    result = run_load(tmp_path, "--clients", "8", "--rate", "100", "--seconds", "6",
                      "--warmup", "1", "--sample-every", "0.5", timeout=120)
    check_rates(result, 8)
    assert result["asta"]["act_per_s"]["min"] > 90


def check_vehicles(result: dict[str, Any], vehicles: int, wall_rate: bool = True) -> None:
    """The P3AT clients: 10 STA per simulated second with no gap beyond a tick, every sensor
    type at the rate its ScanInterval sets, DRIVE streamed, every probe answered, nobody lost."""
    veh, server = result["vehicles"], result["server"]
    assert not veh["lost"] and result["server_alive"]
    assert veh["bots"] == vehicles
    assert veh["sta_per_sim_s"]["n"] == vehicles
    assert veh["sta_per_sim_s"]["min"] >= 9.95, veh["sta_per_sim_s"]
    assert veh["max_gap_sim_s"]["max"] < 0.11, veh["max_gap_sim_s"]
    assert veh["probe_timeouts"] == 0
    for kind in ("GroundTruth", "INS", "Odometry", "RangeScanner"):
        rate, expected = veh[f"sen_{kind}_per_sim_s"], veh[f"sen_{kind}_expected"]
        assert rate["n"] == vehicles, (kind, rate)
        assert expected["min"] > 0, (kind, expected)
        assert rate["min"] >= 0.99 * expected["max"] - 0.05, (kind, rate, expected)
        assert rate["max"] <= 1.01 * expected["min"] + 0.05, (kind, rate, expected)
    drive = veh["drive_per_s"]
    assert drive["min"] > 18 and drive["max"] < 20.5, drive  # a vehicle's controller: 20 Hz
    assert veh["travel_m"]["min"] > 0.1  # the vehicles do move
    wall = veh["sta_per_wall_s"]
    if wall_rate and server["runqueue_wait_percent"] < BUSY_WAIT_PERCENT:
        assert wall["min"] >= 9.5, (wall, server)


@pytest.mark.xdist_group("simulator-load")
def test_arms_and_platforms_together_keep_their_status_and_sensor_rates(tmp_path: Path) -> None:
    result = run_load(tmp_path, "--clients", "6", "--platforms", "2", "--rate", "100",
                      "--seconds", "10", "--warmup", "2", "--sample-every", "0.5", timeout=120)
    check_rates(result, 4)
    check_vehicles(result, 2)
    assert result["asta"]["act_per_s"]["min"] > 90


@pytest.mark.xdist_group("simulator-load")
@pytest.mark.slow
def test_sixty_four_clients_at_100_hz_for_a_minute(tmp_path: Path) -> None:
    result = run_load(tmp_path, "--clients", "64", "--rate", "100", "--seconds", "60",
                      "--warmup", "10", timeout=300)
    # 64 arms take the simulator about 0.93 CPU s per simulated s on these machines: beside the
    # rest of the suite it cannot keep the wall clock, so the wall rates are measured on an idle
    # machine by `make load` (bench/results/load.json) and only the simulated-time rates, the
    # fairness and the flatness are required here.
    check_rates(result, 64, wall_rate=False)
    server = result["server"]
    assert server["threads_max"] == server["threads_first"]  # no thread per client
    assert server["rss_slope_kib_per_min"] < 2048, server  # flat after warm-up (< 2 MiB/min)
    assert server["rss_kib_max"] - server["rss_kib_first"] < 8192, server
