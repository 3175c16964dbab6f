"""``usar-arm sim``: run the embedded USARSim-compatible simulator in the foreground."""

from __future__ import annotations

import argparse
import asyncio
import logging
import signal

from usar_arm.cli.commands import add_command
from usar_arm.cli.common import add_verbosity, setup_logging, verbosity
from usar_arm.core.errors import EXIT_INVALID_INPUT, EXIT_OK, EXIT_UNAVAILABLE, FileFormatError
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.sim.world_spec import load_world

log = logging.getLogger("usar_arm.sim")


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "sim",
        description="Serve the USARSim UDK protocol on TCP (one robot per connection, up to 64) "
                    "with MuJoCo physics, until Ctrl-C or SIGTERM. Robot classes: USARBot.KR60, "
                    "USARBot.Fanuc_M16iB20, USARBot.P3AT, USARBot.FrontAckerman.")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=3000, help="TCP port (default 3000, as UDK)")
    p.add_argument("--speed", type=float, default=1.0,
                   help="simulated seconds per wall-clock second (default 1.0)")
    p.add_argument("--no-gravity", action="store_true", help="switch gravity off")
    p.add_argument("--wire-precision", choices=("udk", "full"), default="udk",
                   help="udk: UDK's number formats (GEO locations truncated to mm, orientations "
                        "to 0.01 rad); full: every number round-trips a float64 (extension)")
    p.add_argument("--world", default=None, metavar="FILE|NAME",
                   help="world file (YAML: start poses, walls and obstacles) or the name of a "
                        "shipped one: default (the arms' cell, no walls), rooms (four rooms "
                        "with doorways and obstacles, for ground vehicles)")
    add_verbosity(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args), default=logging.INFO)
    try:
        options = SimOptions(host=args.host, port=args.port, speed=args.speed,
                             gravity=not args.no_gravity, wire_precision=args.wire_precision)
    except ValueError as exc:
        log.error("%s", exc)
        return EXIT_INVALID_INPUT
    try:
        world = load_world(args.world)
    except (OSError, FileFormatError) as exc:
        log.error("%s", exc)
        return EXIT_INVALID_INPUT
    server = SimServer(options, world_spec=world)

    async def main() -> None:
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, server.stop_from_loop)
        await server.serve()

    try:
        asyncio.run(main())
    except OSError as exc:
        log.error("cannot listen on %s:%d: %s", args.host, args.port, exc.strerror or exc)
        return EXIT_UNAVAILABLE
    return EXIT_OK
