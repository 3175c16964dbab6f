#!/usr/bin/env python3
"""Abuse test of ``usar-arm sim``: bad clients next to well-behaved ones.

The simulator runs in its own process. ``--clients`` well-behaved clients spawn a KR60 each and
stream ACT at ``--rate`` Hz the whole time, while phases of abuse follow one another:

  baseline    nothing else
  junk        malformed, unknown-command, binary and oversized (>64 KiB) lines, 4 clients at once
  midline     clients that send part of a line and vanish (FIN or RST), some after INIT
  flood-act   one client sending --flood valid ACT lines/s for its own robot
  flood-junk  one client sending --flood malformed lines/s
  recovery    nothing else again

For every phase the tool reports the well-behaved clients' ASTA rates (per wall and simulated
second), largest ASTA gap, GETCONF round trip and joint tracking, and for every abusive client
what the server logged about it at disconnect (lines, served, refused by kind).

    python tools/abuse_sim.py --json abuse.json

Exit status: 0 when no well-behaved client lost its connection and the server survived.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import time
from typing import Any

from simharness import (
    Bot,
    Flooder,
    ProcSample,
    ServerProcess,
    campaign,
    disconnect_summaries,
    log_counts,
    machine_load,
    midline_disconnects,
    process_summary,
    sample_server,
    summarise_bots,
    tool_parser,
    write_result,
)

PHASES = ("baseline", "junk", "midline", "flood-act", "flood-junk", "recovery")


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = tool_parser(__doc__, clients=8, rate=100.0)
    p.add_argument("--phase-seconds", type=float, default=4.0, help="length of each phase (4)")
    p.add_argument("--flood", type=float, default=10_000.0,
                   help="lines/s of the flooding clients (default 10000)")
    p.add_argument("--midline-clients", type=int, default=20,
                   help="clients that vanish mid-line (default 20)")
    return p.parse_args(argv)


async def run_abuse(server: ServerProcess, args: argparse.Namespace) -> dict[str, Any]:
    stop = asyncio.Event()
    bots = [Bot(i, rate=args.rate, probe_every=0.5) for i in range(args.clients)]
    samples: list[ProcSample] = []

    sampling = asyncio.create_task(sample_server(server, samples, stop, 0.5))
    tasks = [asyncio.create_task(b.run(server.port, stop)) for b in bots]
    t_start = time.monotonic()
    while any(b.spawned_at is None and b.lost is None for b in bots) \
            and time.monotonic() - t_start < 60:
        await asyncio.sleep(0.05)
    await asyncio.sleep(1.0)  # settle
    windows: dict[str, tuple[float, float]] = {}
    abusers: dict[str, list[Flooder]] = {}
    midline_ports: list[int] = []
    for phase in PHASES:
        phase_stop = asyncio.Event()
        flooders: list[Flooder] = []
        if phase == "junk":
            flooders = [Flooder("malformed", 1000), Flooder("unknown", 1000),
                        Flooder("binary", 300), Flooder("oversized", 5)]
        elif phase == "flood-act":
            flooders = [Flooder("act", args.flood)]
        elif phase == "flood-junk":
            flooders = [Flooder("malformed", args.flood)]
        jobs = [asyncio.create_task(f.run(server.port, phase_stop)) for f in flooders]
        t0 = time.monotonic()
        if phase == "midline":
            midline_ports = await midline_disconnects(server.port, args.midline_clients)
        await asyncio.sleep(max(0.0, t0 + args.phase_seconds - time.monotonic()))
        t1 = time.monotonic()
        phase_stop.set()
        await asyncio.wait(jobs, timeout=10) if jobs else None
        windows[phase] = (t0 + 0.5, t1)  # the first half second lets the abuse start
        abusers[phase] = flooders
        await asyncio.sleep(0.5)
    stop.set()
    await asyncio.wait(tasks, timeout=15)
    sampling.cancel()
    phases: dict[str, Any] = {}
    for phase, (t0, t1) in windows.items():
        phases[phase] = {"window_s": round(t1 - t0, 2),
                         "asta": summarise_bots([b.summary(t0, t1) for b in bots]),
                         "server": process_summary([s for s in samples if s.t <= t1], t0),
                         "abusers": [{"kind": f.kind, "rate_asked": f.rate,
                                      "sent_lines": f.sent_lines, "sent_bytes": f.sent_bytes,
                                      "achieved_rate": round(f.achieved_rate, 1),
                                      "port": f.local_port, "lost": f.lost}
                                     for f in abusers[phase]]}
    return {"clients": args.clients, "rate_hz": args.rate, "phase_seconds": args.phase_seconds,
            "flood": args.flood, "phases": phases, "midline_ports": midline_ports,
            "lost": summarise_bots([b.summary(t_start, time.monotonic()) for b in bots])["lost"],
            "server_samples": [[round(s.t - t_start, 2), s.rss_kib, s.threads]
                               for s in samples]}


def attach_server_log(result: dict[str, Any], text: str) -> None:
    """Add what the server logged about each abusive client (by port) to the phases."""
    summaries = disconnect_summaries(text)
    for phase in result["phases"].values():
        for abuser in phase["abusers"]:
            abuser["server"] = summaries.get(abuser["port"])
    result["midline_server"] = [summaries.get(p) for p in result["midline_ports"]]
    result["server_log_counts"] = log_counts(text)
    result["server_log_lines"] = text.count("\n")
    result["left_mid_line_logged"] = text.count("left mid-line")


def print_summary(result: dict[str, Any]) -> None:
    out = [f"{result['clients']} well-behaved clients x {result['rate_hz']:g} Hz; "
           f"load {result['load_after']}",
           f"{'phase':<11} {'ASTA/wall s':>17} {'ASTA/sim s':>17} {'max gap s':>7} "
           f"{'rtt p50 ms':>10} {'track mrad':>10}  abusers: sent -> served/refused"]
    for name, ph in result["phases"].items():
        a = ph["asta"]

        def rng(k: str, a: dict[str, Any] = a) -> str:
            v = a[k]
            return f"{v['min']:.2f}-{v['max']:.2f}" if v.get("n") else "-"

        abusers = "; ".join(
            f"{ab['kind']} {ab['sent_lines']} -> "
            + (f"{ab['server']['served']}/{ab['server']['refused']}" if ab.get("server")
               else "?") for ab in ph["abusers"])
        out.append(f"{name:<11} {rng('asta_per_wall_s'):>17} {rng('asta_per_sim_s'):>17} "
                   f"{a['max_gap_wall_s'].get('max', 0):>7.3f} "
                   f"{a['rtt_ms_median'].get('median', 0):>10.2f} "
                   f"{a['track_rms_mrad'].get('median', 0):>10.1f}  {abusers}")
    out.append(f"lost: {result['lost'] or 'none'}; server log {result['server_log_lines']} lines "
               f"({result['server_log']})")
    sys.stderr.write("\n".join(out) + "\n")


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    load_before = machine_load()
    result, server, code, log_path = campaign("abuse_sim", args.server_log,
                                              lambda server: run_abuse(server, args))
    result.update(server_exit=code, server_log=str(log_path), load_before=load_before,
                  load_after=machine_load())
    attach_server_log(result, server.log_text())
    write_result(result, args.json)
    print_summary(result)
    return 0 if not result["lost"] and result["server_alive"] else 1


if __name__ == "__main__":
    sys.exit(main())
