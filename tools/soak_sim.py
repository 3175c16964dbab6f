#!/usr/bin/env python3
"""Soak test of ``usar-arm sim``: hours of steady clients, churn and a little abuse.

The simulator runs in its own process. ``--clients`` steady clients spawn a KR60 each and stream
ACT at ``--rate`` Hz for the whole run (they must never lose their connection); every
``--churn-every`` seconds another client connects, spawns, streams for ``--churn-seconds`` and
leaves (robots are created and destroyed all the time); every ``--abuse-every`` seconds a short
burst of junk arrives (malformed and binary lines, an oversized line, a client vanishing
mid-line). The server's RSS, thread count and CPU time are sampled every ``--sample-every``
seconds; after ``--warmup`` minutes their slopes must stay flat.

    python tools/soak_sim.py --minutes 10 --json soak.json      # as the slow test suite runs it
    python tools/soak_sim.py --minutes 240                      # by hand

Exit status: 0 when no steady client lost its connection, every churn client spawned, the server
survived and logged no error; 1 otherwise (the JSON says which).
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import time
from typing import Any

from simharness import (
    Bot,
    Flooder,
    ProcSample,
    ServerProcess,
    campaign,
    log_counts,
    machine_load,
    midline_disconnects,
    process_summary,
    quantiles,
    sample_rows,
    sample_server,
    summarise_bots,
    tool_parser,
    write_result,
)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = tool_parser(__doc__, clients=4, rate=50.0)
    p.add_argument("--minutes", type=float, default=10.0, help="length of the run (default 10)")
    p.add_argument("--churn-every", type=float, default=5.0,
                   help="seconds between short-lived clients (default 5; 0: none)")
    p.add_argument("--churn-seconds", type=float, default=2.0,
                   help="how long each short-lived client streams (default 2)")
    p.add_argument("--abuse-every", type=float, default=15.0,
                   help="seconds between bursts of junk (default 15; 0: none)")
    p.add_argument("--sample-every", type=float, default=5.0,
                   help="seconds between RSS/thread/CPU samples (default 5)")
    p.add_argument("--warmup", type=float, default=2.0,
                   help="minutes left out of the slopes (default 2)")
    return p.parse_args(argv)


async def run_soak(server: ServerProcess, args: argparse.Namespace) -> dict[str, Any]:
    stop = asyncio.Event()
    port = server.port
    bots = [Bot(i, rate=args.rate, probe_every=2.0) for i in range(args.clients)]
    samples: list[ProcSample] = []
    churn: list[Bot] = []
    bursts = 0
    started = time.monotonic()
    end = started + 60.0 * args.minutes

    async def one_churn(bot: Bot) -> None:
        leave = asyncio.Event()
        job = asyncio.create_task(bot.run(port, leave, spawn_timeout=30))
        await asyncio.sleep(args.churn_seconds)
        leave.set()
        await asyncio.wait([job], timeout=10)

    async def churner() -> None:
        """A new client every ``churn_every`` s (on a fixed schedule; they may overlap)."""
        n = 0
        first = time.monotonic()
        jobs = []
        while first + (n + 1) * args.churn_every + args.churn_seconds < end:
            await asyncio.sleep(max(0.0, first + (n + 1) * args.churn_every - time.monotonic()))
            bot = Bot(1000 + n, rate=args.rate, probe_every=0.5)
            n += 1
            churn.append(bot)
            jobs.append(asyncio.create_task(one_churn(bot)))
        if jobs:
            await asyncio.wait(jobs, timeout=args.churn_seconds + 15)

    async def abuser() -> None:
        nonlocal bursts
        while time.monotonic() + args.abuse_every < end:
            await asyncio.sleep(args.abuse_every)
            burst_stop = asyncio.Event()
            junk = [Flooder("malformed", 200), Flooder("binary", 50), Flooder("oversized", 1)]
            jobs = [asyncio.create_task(f.run(port, burst_stop)) for f in junk]
            await midline_disconnects(port, 2)
            await asyncio.sleep(1.0)
            burst_stop.set()
            await asyncio.wait(jobs, timeout=10)
            bursts += 1

    helpers = [asyncio.create_task(sample_server(server, samples, stop, args.sample_every))]
    tasks = [asyncio.create_task(b.run(port, stop)) for b in bots]
    if args.churn_every > 0:
        helpers.append(asyncio.create_task(churner()))
    if args.abuse_every > 0:
        helpers.append(asyncio.create_task(abuser()))
    last_report = started
    while time.monotonic() < end and server.alive():
        await asyncio.sleep(1.0)
        if sys.stderr.isatty() and time.monotonic() - last_report > 30:
            last_report = time.monotonic()
            s = samples[-1] if samples else None
            sys.stderr.write(f"{(last_report - started) / 60:5.1f} min: RSS "
                             f"{s.rss_kib if s else '?'} KiB, threads {s.threads if s else '?'}, "
                             f"churn {len(churn)}, lost {sum(1 for b in bots if b.lost)}\n")
    stop.set()
    await asyncio.wait(tasks, timeout=15)
    for h in helpers:
        h.cancel()
    finished = time.monotonic()
    warm = started + 60.0 * min(args.warmup, args.minutes / 2)
    minutes = []  # per steady client and whole minute: ASTA per wall and simulated second
    t = warm
    while t + 60.0 <= finished:
        rows = [b.summary(t, t + 60.0) for b in bots]
        minutes.append({"asta_per_wall_s": quantiles([r["asta_per_wall_s"] for r in rows
                                                      if "asta_per_wall_s" in r]),
                        "asta_per_sim_s": quantiles([r["asta_per_sim_s"] for r in rows
                                                     if "asta_per_sim_s" in r])})
        t += 60.0
    churn_spawned = sum(1 for b in churn if b.spawned_at is not None)
    return {
        "minutes": args.minutes, "clients": args.clients, "rate_hz": args.rate,
        "steady": summarise_bots([b.summary(warm, finished) for b in bots]),
        "per_minute": minutes,
        "churn": {"clients": len(churn), "spawned": churn_spawned,
                  "failed": [f"churn {b.index}: {b.lost}" for b in churn
                             if b.spawned_at is None],
                  "spawn_s": quantiles([b.spawned_at - b._t0 for b in churn
                                        if b.spawned_at is not None])},
        "abuse_bursts": bursts,
        "server": process_summary(samples, warm),
        "server_samples": sample_rows(samples, started, 1),
        "rss_kib_median_after_warmup": statistics.median(
            [s.rss_kib for s in samples if s.t >= warm] or [0]),
    }


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    load_before = machine_load()
    result, server, code, log_path = campaign("soak_sim", args.server_log,
                                              lambda server: run_soak(server, args))
    text = server.log_text()
    result.update(server_exit=code, server_log=str(log_path), load_before=load_before,
                  load_after=machine_load(), server_log_counts=log_counts(text),
                  server_log_lines=text.count("\n"))
    write_result(result, args.json)
    st, sv, ch = result["steady"], result["server"], result["churn"]
    sys.stderr.write(
        f"soak {args.minutes:g} min, {args.clients} steady clients x {args.rate:g} Hz, "
        f"{ch['clients']} churn clients ({ch['spawned']} spawned), {result['abuse_bursts']} "
        f"abuse bursts; load {result['load_after']}\n"
        f"  steady ASTA per wall s {st['asta_per_wall_s']}, per sim s {st['asta_per_sim_s']}\n"
        f"  lost connections: {st['lost'] or 'none'}\n"
        f"  server RSS {sv.get('rss_kib_first')} -> {sv.get('rss_kib_last')} KiB, slope "
        f"{sv.get('rss_slope_kib_per_min')} KiB/min; threads {sv.get('threads_first')} -> "
        f"{sv.get('threads_last')}; CPU {sv.get('cpu_percent')} %\n"
        f"  server log: {result['server_log_counts']} ({log_path})\n")
    counts = result["server_log_counts"]
    ok = (not st["lost"] and not ch["failed"] and result["server_alive"]
          and counts["errors"] == 0 and counts["tracebacks"] == 0)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
