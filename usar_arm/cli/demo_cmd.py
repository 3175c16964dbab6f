"""``usar-arm demo``: the main job on the embedded simulator."""

from __future__ import annotations

import argparse
import time

from usar_arm.cli.common import add_verbosity, err, out, setup_logging, verbosity
from usar_arm.errors import EXIT_OK
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser("demo", help="run the main job on the embedded simulator",
                       description="Start the embedded simulator, spawn the KR60 and show its "
                                   "status stream while one joint moves.")
    p.add_argument("--seconds", type=float, default=3.0, help="how long to stream (s)")
    add_verbosity(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    with SimServer(SimOptions(port=0)) as server, UsarClient(port=server.port) as client:
        err(f"embedded simulator listening on 127.0.0.1:{server.port}")
        client.spawn("USARBot.KR60", "KR60", start="RobotStart1")
        client.subscribe(lambda r: out(r.line) if isinstance(r.message, (m.Asta, m.Sen)) else None)
        client.act("KR60Arm", {0: 0.5})
        time.sleep(args.seconds)
    return EXIT_OK
