"""``usar-arm drive``: drive a ground vehicle (the P3AT) by waypoints or a velocity script,
record the run as a rosbag2, draw it, and report how far odometry and INS drifted."""

from __future__ import annotations

import argparse
import contextlib
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from usar_arm.cli.commands import add_command
from usar_arm.cli.common import add_verbosity, out, print_json, progress, setup_logging, verbosity
from usar_arm.cli.progress_bar import ProgressBar
from usar_arm.control.drive_inputs import check_in_world, load_script, parse_waypoints
from usar_arm.control.drive_record import Drift, DriveRecord, drift, odom_in_map
from usar_arm.control.drive_run import DriveOptions, Driver
from usar_arm.control.pursuit import PursuitOptions
from usar_arm.control.vehicle_wire import vehicle_info
from usar_arm.core.errors import (
    EXIT_EXECUTION_ABORTED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    InvalidInputError,
    UnknownRobotError,
)
from usar_arm.core.world_file import Scenery, load_scenery
from usar_arm.discover.platform import learn_platform
from usar_arm.usarsim.client import UsarClient


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "drive",
        description="Spawn a ground vehicle, drive it through --waypoints (pure pursuit) or "
                    "by a velocity --script, record its ground truth, odometry, INS, laser "
                    "scans and commands (a rosbag2 with -o), draw the run over the world "
                    "(--picture) and report the odometry and INS drift against the ground "
                    "truth. Waypoints are in the map frame (REP-103: the world file's x, and its "
                    "y negated), metres. Ctrl-C stops the vehicle and keeps what was recorded.")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--waypoints", nargs="+", metavar="X,Y",
                      help="waypoints x,y (m, map frame), or one file of them (YAML list of "
                           "[x, y], or CSV rows x,y)")
    what.add_argument("--script", metavar="FILE",
                      help="velocity script: YAML list of [duration s, v m/s, w rad/s], or CSV "
                           "rows duration,v,w")
    p.add_argument("--robot", default="P3AT",
                   help="vehicle class (USARBot. is added when missing; default P3AT)")
    p.add_argument("--host", default=None,
                   help="USARSim server; without it the embedded simulator is started")
    p.add_argument("--port", type=int, default=3000, help="server port (default 3000)")
    p.add_argument("--world", default="rooms", metavar="FILE|NAME",
                   help="world file or shipped world (default rooms): the embedded "
                        "simulator's map, the picture's outline and the waypoints' check")
    p.add_argument("--start-position", default=None, metavar="NAME",
                   help="start pose to spawn at; default: the server's first")
    p.add_argument("--speed", type=float, default=1.0, metavar="X",
                   help="embedded simulator: simulated seconds per wall second (default 1)")
    p.add_argument("--timeout", type=float, default=5.0, metavar="S",
                   help="seconds any single wait for the server may take (default 5)")
    p.add_argument("--localisation", choices=("truth", "odometry", "ins"), default="truth",
                   help="pose the pursuit steers on (default truth)")
    p.add_argument("--lookahead", type=float, default=0.5, metavar="M",
                   help="pure pursuit lookahead distance (m, default 0.5)")
    p.add_argument("--max-speed", type=float, default=0.5, metavar="M/S",
                   help="forward speed asked (m/s, default 0.5; the wheels' limit caps it)")
    p.add_argument("--goal-tolerance", type=float, default=0.1, metavar="M",
                   help="distance (m) within which the last waypoint is reached (default 0.1)")
    p.add_argument("--turn-in-place", type=float, default=30.0, metavar="DEG",
                   help="bearing (degrees) beyond which the vehicle turns on the spot "
                        "(default 30)")
    p.add_argument("-o", "--out", default=None, metavar="DIR", help="write a rosbag2 folder")
    p.add_argument("--overwrite", action="store_true", help="replace an existing bag")
    p.add_argument("--picture", default="drive.png", metavar="PNG",
                   help="the picture of the run (default drive.png; '' for none)")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    add_verbosity(p)
    p.set_defaults(handler=run)


def _class_name(robot: str) -> str:
    return robot if "." in robot else f"USARBot.{robot}"


@contextlib.contextmanager
def _server(args: argparse.Namespace) -> Iterator[tuple[str, int, tuple[str, ...]]]:
    """(host, port, classes the server is known to have) of the server to drive on."""
    if args.host is not None:
        yield args.host, args.port, ()
        return
    from usar_arm.description.embedded import embedded_simulator, known_classes

    known = known_classes(vehicles=True)
    if _class_name(args.robot) not in known:
        raise UnknownRobotError(_class_name(args.robot), known,
                                "the embedded simulator has no such class")
    with embedded_simulator(world=args.world, speed=args.speed) as server:
        assert server.port is not None
        yield "127.0.0.1", server.port, known


def _drive(args: argparse.Namespace, waypoints: Any, script: Any) -> DriveRecord:
    options = DriveOptions(localisation=args.localisation, timeout_s=args.timeout)
    pursuit = PursuitOptions(args.lookahead, args.max_speed, args.goal_tolerance,
                             turn_in_place_rad=math.radians(args.turn_in_place))
    bar = ProgressBar("cm" if script is None else "ds", enabled=verbosity(args) >= 0)
    with _server(args) as (host, port, known), \
            UsarClient(host, port, timeout=args.timeout) as client:
        _, desc = learn_platform(client, _class_name(args.robot), args.start_position,
                                 args.timeout, known)
        vehicle = vehicle_info(desc)
        driver = Driver(client, vehicle, options)
        try:
            if script is not None:
                return driver.play(script, bar)
            return driver.follow(waypoints, pursuit, bar)
        finally:
            bar.close()


def summary(record: DriveRecord, drifts: list[Drift]) -> dict[str, Any]:
    """The run in numbers (stable keys; m, s, rad, rad/s)."""
    cmds, v = record.commands, record.vehicle
    return {
        "robot": v.name, "reached": record.reached, "interrupted": record.interrupted,
        "distance_m": record.truth.length_m(),
        "duration_s": float(record.truth.t[-1] - record.truth.t[0]) if len(record.truth) else 0,
        "waypoints": [list(g) for g in record.goals],
        "drift": {d.source: {"position_m": d.position_m, "heading_rad": d.heading_rad,
                             "percent_of_distance": d.percent_of_distance} for d in drifts},
        "commands": {"count": len(cmds), "clamped": sum(c.clamped for c in cmds),
                     "max_wheel_speed_radps": v.max_wheel_speed,
                     "largest_sent_radps": max((max(abs(c.left), abs(c.right)) for c in cmds),
                                               default=0.0)},
        "vehicle": {"steering": v.steering, "wheel_radius_m": v.wheel_radius,
                    "wheel_separation_m": v.wheel_separation, "wheel_base_m": v.wheel_base,
                    "max_steer_rad": v.max_steer,
                    "scanner": v.scanner.name if v.scanner else None},
        "scans": len(record.scans)}


def _write(args: argparse.Namespace, record: DriveRecord, drifts: list[Drift],
           scenery: Scenery | None) -> dict[str, str]:
    written = {}
    if args.out:
        from usar_arm.export.drive_bag import write_drive_bag  # rosbags: only when writing

        written["bag"] = str(write_drive_bag(args.out, record, overwrite=args.overwrite).path)
    if args.picture:
        from usar_arm.export.drive_plot import plot_drive  # matplotlib: only when drawing

        steering = "a script" if args.script else {
            "truth": "the ground truth", "odometry": "the odometry", "ins": "the INS"
        }[args.localisation]
        plot_drive(args.picture, record, scenery, drifts,
                   title=f"{record.vehicle.name} steered on {steering}")
        written["picture"] = args.picture
    return written


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    waypoints = parse_waypoints(args.waypoints) if args.waypoints else None
    script = load_script(args.script) if args.script else None
    scenery = load_scenery(args.world) if args.world else None
    if waypoints is not None and scenery is not None:
        check_in_world(waypoints, scenery, args.world)
    if args.out and Path(args.out).exists() and not args.overwrite:
        raise InvalidInputError(f"{args.out} exists already (pass --overwrite to replace it)")
    record = _drive(args, waypoints, script)
    drifts = [d for d in (drift("odometry", odom_in_map(record), record.truth),
                          drift("INS", record.ins, record.truth)) if d is not None]
    result = summary(record, drifts) | {"written": _write(args, record, drifts, scenery)}
    if args.json:
        print_json(result)
    else:
        _print(result)
    if record.interrupted:
        progress("usar-arm: interrupted; the vehicle was stopped and the record kept")
        return EXIT_INTERRUPTED
    if not record.reached:
        progress("usar-arm: error: the drive ran out of time before its goal (blocked?)")
        return EXIT_EXECUTION_ABORTED
    return EXIT_OK


def _print(r: dict[str, Any]) -> None:
    goal = "reached its goal" if r["reached"] else "did NOT reach its goal"
    out(f"{r['robot']} drove {r['distance_m']:.2f} m in {r['duration_s']:.1f} s (simulated) "
        f"and {goal}")
    for source, d in r["drift"].items():
        out(f"{source} drift: {d['position_m']:.3f} m ({d['percent_of_distance']:.2f} % of the "
            f"distance), heading {d['heading_rad']:+.3f} rad")
    c = r["commands"]
    out(f"wheel commands: {c['count']}, {c['clamped']} scaled to the limit; largest "
        f"{c['largest_sent_radps']:.4f} rad/s of {c['max_wheel_speed_radps']:.4f}")
    for what, path in r["written"].items():
        out(f"wrote {what} {path}")
