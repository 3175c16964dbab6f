"""``usar-arm urdf`` for a ground vehicle: learn it, write its URDF, say what was learnt."""

from __future__ import annotations

import argparse
import logging

from usar_arm.cli.common import err, out, print_json
from usar_arm.core.errors import EXIT_OK
from usar_arm.description.pipeline import DescribeOptions
from usar_arm.description.platform import PlatformResult, learn, write_platform

log = logging.getLogger("usar_arm.cli")


def _facts(result: PlatformResult) -> dict[str, object]:
    d = result.description
    return {"robot": d.name, "class": d.robot_class, "type": d.platform_type,
            "steering": d.steering_type, "mass_kg": d.mass, "max_wheel_speed_rad_s": d.max_speed,
            "wheel_radius_m": d.wheel_radius, "wheel_separation_m": d.wheel_separation,
            "wheel_base_m": d.wheel_base, "footprint_radius_m": round(d.footprint_radius, 4),
            "max_front_steer_rad": d.max_front_steer,
            "sensors": [{"type": s.type, "name": s.name, "frame": result.frames.sensor(s),
                         "xyz": list(s.xyz), "rpy": list(s.rpy)} for s in d.sensors],
            "hidden_sensors": list(d.hidden), "unknown_sensors": list(d.unknown)}


def run_platform_urdf(args: argparse.Namespace, options: DescribeOptions) -> int:
    """Learn the vehicle ``options`` name and write its files into ``args.out_dir``."""
    err(f"discovering {options.robot_class} (a ground vehicle) on "
        f"{'the embedded simulator' if options.host is None else f'{args.host}:{args.port}'}...")
    result = learn(options.robot_class, options.host, options.port, options.start,
                   options.timeout, options.wire_precision)
    paths = write_platform(result, args.out_dir)
    facts = _facts(result)
    for what in ("hidden_sensors", "unknown_sensors"):
        for comp in facts[what]:  # type: ignore[attr-defined]
            log.warning("%s: %s (no frame in the URDF)", what.replace("_", " ")[:-1], comp)
    if args.json:
        print_json({**facts, "files": {k: str(p) for k, p in paths.items()}})
        return EXIT_OK
    d = result.description
    out(f"{d.name} ({d.robot_class}): {d.platform_type}, {d.steering_type}, {d.mass:g} kg, "
        f"wheels r {d.wheel_radius:g} m, separation {d.wheel_separation:g} m, base "
        f"{d.wheel_base:g} m, at most {d.max_speed:g} rad/s"
        + (f", front steer +-{d.max_front_steer:g} rad" if d.ackermann else ""))
    for s in d.sensors:
        out(f"  sensor {s.type:<12} {s.name:<10} frame {result.frames.sensor(s):<16} "
            f"xyz {', '.join(f'{v:g}' for v in s.xyz)}")
    for comp in d.hidden:
        out(f"  hidden sensor (GETGEO gave nothing): {comp}")
    for comp in d.unknown:
        out(f"  sensor of an unknown type (not described): {comp}")
    for kind, path in paths.items():
        out(f"wrote {path}  ({kind})")
    return EXIT_OK
