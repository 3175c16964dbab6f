#!/usr/bin/env python3
"""Load test of ``usar-arm sim``: N clients, each spawning a KR60 and streaming ACT, or a P3AT
and driving it.

The simulator runs in its own process (started here, or one already running with ``--port``);
the clients share one asyncio loop in this process. Per client the tool measures the ASTA rate
per wall second and per simulated second (from ``{Time t}``), the largest gap between ASTAs, the
GETCONF round trip, and how closely joint 1 follows its commanded sine; of the server it samples
RSS, thread count and CPU time. With ``--platforms K``, K of the N clients spawn a P3AT in the
``rooms`` world instead and drive it (DRIVE at ``--rate``, at most 20 Hz); of those the tool
measures the STA rate and gaps, each sensor type's SEN rate per simulated second against its
ScanInterval, and the GETCONF round trip. Optionally one more client floods the server.

    python tools/load_sim.py --clients 64 --platforms 16 --rate 100 --seconds 60 --json load.json

Exit status: 0 when every client kept its connection and the server survived, 1 otherwise.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from simharness import (
    FLOOD_KINDS,
    VEHICLE_FIGURES,
    Bot,
    Driver,
    Flooder,
    ProcSample,
    ServerProcess,
    log_counts,
    machine_load,
    process_summary,
    sample_rows,
    sample_server,
    summarise_bots,
    tool_parser,
    write_result,
)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = tool_parser(__doc__, clients=64, rate=100.0,
                    epilog="Results: one JSON object (--json FILE, else stdout); "
                           "a short summary on stderr.")
    p.add_argument("--seconds", type=float, default=60.0,
                   help="streaming time once every robot exists (default 60)")
    p.add_argument("--warmup", type=float, default=5.0,
                   help="seconds at the start left out of rates and slopes (default 5)")
    p.add_argument("--probe-every", type=float, default=1.0,
                   help="seconds between GETCONF round-trip probes per client (0: none)")
    p.add_argument("--sample-every", type=float, default=2.0,
                   help="seconds between RSS/thread/CPU samples of the server (default 2)")
    p.add_argument("--speed", type=float, default=1.0, help="--speed of the simulator")
    p.add_argument("--port", type=int, default=0,
                   help="use a simulator already listening on this port (no process figures)")
    p.add_argument("--platforms", type=int, default=0,
                   help="of the clients, this many spawn a P3AT in the rooms world and drive it "
                        "(DRIVE at --rate, at most 20 Hz) instead of a KR60 (default 0; with "
                        "--port, that simulator must have RobotStart1-3, e.g. --world rooms)")
    p.add_argument("--flood", type=float, default=0.0,
                   help="one more client sends this many lines/s (e.g. 10000)")
    p.add_argument("--flood-kind", choices=FLOOD_KINDS, default="act",
                   help="what the flooding client sends (default act: valid ACT lines)")
    args = p.parse_args(argv)
    if not 0 <= args.platforms <= args.clients:
        p.error(f"--platforms must be within 0..--clients ({args.clients})")
    return args


def make_clients(args: argparse.Namespace) -> tuple[list[Bot], list[Driver]]:
    """The arm clients (0 .. N-K-1) and the vehicle clients (N-K .. N-1)."""
    arms = args.clients - args.platforms
    return ([Bot(i, rate=args.rate, probe_every=args.probe_every) for i in range(arms)],
            [Driver(i, rate=args.rate, probe_every=args.probe_every)
             for i in range(arms, args.clients)])


async def run_load(port: int, server: ServerProcess | None, args: argparse.Namespace
                   ) -> dict[str, Any]:
    stop = asyncio.Event()
    arms, vehicles = make_clients(args)
    bots = [*arms, *vehicles]
    samples: list[ProcSample] = []

    started = time.monotonic()
    cpu0 = time.process_time()
    sampling = asyncio.create_task(sample_server(server, samples, stop, args.sample_every))
    tasks = [asyncio.create_task(b.run(port, stop)) for b in bots]
    while (any(b.spawned_at is None and b.lost is None for b in bots)
           and time.monotonic() - started < 120):
        await asyncio.sleep(0.1)
    ready = time.monotonic()
    flooder = None
    if args.flood > 0:
        flooder = Flooder(args.flood_kind, args.flood)
        tasks.append(asyncio.create_task(flooder.run(port, stop)))
    await asyncio.sleep(args.seconds)
    end = time.monotonic()
    stop.set()
    await asyncio.wait(tasks, timeout=15)
    sampling.cancel()
    t0 = ready + min(args.warmup, args.seconds / 2)
    rows = [b.summary(t0, end) for b in arms]
    vehicle_rows = [b.summary(t0, end) for b in vehicles]
    result: dict[str, Any] = {
        "clients": args.clients, "platforms": args.platforms, "rate_hz": args.rate,
        "seconds": args.seconds,
        "spawn_s": round(ready - started, 2), "window_s": round(end - t0, 2),
        "load_before": args.load_before, "load_after": machine_load(),
        "asta": summarise_bots(rows),
        "vehicles": summarise_bots(vehicle_rows, VEHICLE_FIGURES),
        "server": process_summary(samples, t0),
        "client_cpu_percent": round(100 * (time.process_time() - cpu0) / (end - started), 1),
        "server_samples": sample_rows(samples, started),
        "per_client": rows,
        "per_vehicle": vehicle_rows,
    }
    speed = result["asta" if rows else "vehicles"].get("sim_speed", {}).get("median")
    if result["server"] and speed:
        result["server"]["cpu_s_per_sim_s"] = round(
            result["server"]["cpu_percent"] / 100 / speed, 3)
    if flooder is not None:
        result["flood"] = {"kind": flooder.kind, "rate": flooder.rate,
                           "sent_lines": flooder.sent_lines, "sent_bytes": flooder.sent_bytes,
                           "lost": flooder.lost}
    return result


def spread(summary: dict[str, Any], key: str, fmt: str = ".3f") -> str:
    """``min / median / max`` of one summarised figure ("-" when no client has it)."""
    v = summary.get(key, {})
    return " / ".join(format(v[k], fmt) for k in ("min", "median", "max")) if v.get("n") else "-"


def arm_lines(a: dict[str, Any]) -> list[str]:
    """The stderr summary of the arm clients (``asta``)."""
    return [
        f"  arms ({a['bots']}): min/med/max",
        f"  ASTA per wall s   {spread(a, 'asta_per_wall_s')}",
        f"  ASTA per sim s    {spread(a, 'asta_per_sim_s')}",
        f"  sim speed         {spread(a, 'sim_speed')}",
        f"  ASTA max gap (s)  {spread(a, 'max_gap_wall_s')}",
        f"  ACT sent per s    {spread(a, 'act_per_s')}",
        f"  GETCONF rtt p50ms {spread(a, 'rtt_ms_median')}",
        f"  GETCONF rtt max   {spread(a, 'rtt_ms_max')}",
        f"  joint-1 track rms {spread(a, 'track_rms_mrad')} mrad",
        f"  lost connections  {len(a['lost'])} {a['lost'][:3]}",
    ]


def vehicle_lines(v: dict[str, Any]) -> list[str]:
    """The stderr summary of the vehicle clients (``vehicles``): STA, each SEN type's rate
    against its expected rate, DRIVE and GETCONF."""
    sens = sorted(k[4:-len("_per_sim_s")] for k in v if k.startswith("sen_")
                  and k.endswith("_per_sim_s"))
    return [
        f"  vehicles ({v['bots']}): min/med/max",
        f"  STA per wall s    {spread(v, 'sta_per_wall_s')}",
        f"  STA per sim s     {spread(v, 'sta_per_sim_s')}",
        f"  STA max gap wall  {spread(v, 'max_gap_wall_s')} s, sim "
        f"{spread(v, 'max_gap_sim_s')} s",
        *(f"  SEN {kind:<13} {spread(v, f'sen_{kind}_per_sim_s')} per sim s (expected "
          f"{spread(v, f'sen_{kind}_expected', '.1f')})" for kind in sens),
        f"  DRIVE sent per s  {spread(v, 'drive_per_s')}",
        f"  path driven (m)   {spread(v, 'travel_m', '.2f')}",
        f"  nearest scan (m)  {spread(v, 'closest_m', '.2f')}",
        f"  GETCONF rtt p50ms {spread(v, 'rtt_ms_median')}",
        f"  GETCONF rtt max   {spread(v, 'rtt_ms_max')}",
        f"  lost connections  {len(v['lost'])} {v['lost'][:3]}",
    ]


def print_summary(result: dict[str, Any]) -> None:
    s = result.get("server", {})
    lines = [
        f"{result['clients']} clients ({result['platforms']} of them P3ATs) x "
        f"{result['rate_hz']:g} Hz, window {result['window_s']} s (spawn took "
        f"{result['spawn_s']} s); load {result['load_before']} -> {result['load_after']}",
    ]
    if result["asta"]["bots"]:
        lines += arm_lines(result["asta"])
    if result["vehicles"]["bots"]:
        lines += vehicle_lines(result["vehicles"])
    if s:
        lines.append(f"  server CPU {s['cpu_percent']} % ({s.get('cpu_s_per_sim_s')} CPU s per "
                     f"simulated s; waited for a CPU {s['runqueue_wait_percent']} % of the time)"
                     f"; client CPU {result['client_cpu_percent']} %")
        lines.append(f"  server RSS {s['rss_kib_first']}->"
                     f"{s['rss_kib_last']} KiB (slope {s['rss_slope_kib_per_min']} KiB/min), "
                     f"threads {s['threads_first']}->{s['threads_last']}")
    if "server_log" in result:
        lines.append(f"  server log: {result['server_log']}")
    sys.stderr.write("\n".join(lines) + "\n")


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    args.load_before = machine_load()
    server = None
    log_path = args.server_log or Path(tempfile.mkdtemp(prefix="load_sim_")) / "sim.log"
    if not args.port:
        world = ("--world", "rooms") if args.platforms else ()
        server = ServerProcess(log_path, speed=args.speed, extra_args=world)
    port = args.port or server.port  # type: ignore[union-attr]
    try:
        result = asyncio.run(run_load(port, server, args))
        result["server_alive"] = server.alive() if server else None
    finally:
        code = server.stop() if server else None
    if server is not None:
        text = server.log_text()
        result["server_exit"] = code
        result["server_log"] = str(log_path)
        result["server_log_counts"] = log_counts(text)
    write_result(result, args.json)
    print_summary(result)
    ok = (not result["asta"]["lost"] and not result["vehicles"]["lost"]
          and result.get("server_alive") is not False)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
