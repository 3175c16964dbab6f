"""``usar-arm tesseract-config``: a Tesseract (ROS-Industrial) config folder for a robot."""

from __future__ import annotations

import argparse
from pathlib import Path

from usar_arm.cli.commands import add_command
from usar_arm.cli.common import add_verbosity, err, out, print_json, setup_logging, verbosity
from usar_arm.cli.default_calibration import add_calibration_args, config_description
from usar_arm.cli.out_folder import check_out_folder, other_files, report_other_files
from usar_arm.cli.robot_args import add_description_args, add_server_args
from usar_arm.core.errors import EXIT_OK, FileFormatError
from usar_arm.core.fileio import write_tree_atomic
from usar_arm.planning.robot import Robot, robot_from_files
from usar_arm.urdf.tesseract import TesseractOptions, tesseract_config
from usar_arm.urdf.tesseract_package import check_package_name


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "tesseract-config",
        description="Discover ROBOT and describe it as `usar-arm urdf` does (calibrated "
                    "through its tip sensor by default: the description cache's calibration "
                    "when it holds one, else a tour; --no-calibrate: as learnt), or read "
                    "--urdf/--srdf, and write a "
                    "Tesseract config folder into DIR: the URDF, the SRDF with Tesseract's "
                    "kinematics_plugin_config and contact_managers_plugin_config entries, the "
                    "kinematics plugins (OPW inverse kinematics when the arm is OPW within "
                    "--opw-tolerance, measured against its own forward kinematics; KDL "
                    "otherwise), the contact managers, task composer pipelines, package.xml, "
                    "plan_example.py and a README. DIR's name is the package name its "
                    "package:// URLs use (REP-144: lowercase letters, digits and '_', "
                    "starting with a letter). DIR must be new, empty or a folder this command "
                    "wrote: its files are replaced, any other file is kept and listed.")
    add_server_args(p)
    add_description_args(p)
    add_calibration_args(p)
    p.add_argument("--urdf", default=None, metavar="FILE",
                   help="describe this URDF instead of discovering the robot (its SRDF is read "
                        "from beside it unless --srdf is given)")
    p.add_argument("--srdf", default=None, metavar="FILE",
                   help="SRDF for --urdf (only with --urdf)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="folder to write; its name is the package name")
    p.add_argument("--opw-tolerance", type=float, nargs=2, default=(1e-6, 1e-6),
                   metavar=("M", "RAD"),
                   help="largest deviation of OPW forward kinematics from the arm's (position "
                        "in m, rotation in rad) for OPW to be chosen (default 1e-6 1e-6)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    add_verbosity(p)
    p.set_defaults(handler=run, usage_error=p.error)


def _from_files(args: argparse.Namespace) -> tuple[Robot, str]:
    """The Robot of --urdf and its SRDF's text."""
    robot = robot_from_files(args.urdf, args.srdf)
    srdf_path = Path(args.srdf) if args.srdf else Path(args.urdf).with_name(
        Path(args.urdf).name.removesuffix(".urdf") + ".srdf")
    if not srdf_path.is_file():
        raise FileFormatError(str(srdf_path), "no SRDF beside the URDF: Tesseract needs its "
                                              "groups and disabled collisions (give --srdf)")
    return robot, srdf_path.read_text()


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    if args.srdf and not args.urdf:
        args.usage_error("--srdf goes with --urdf (the SRDF of that URDF); a discovered robot "
                         "brings its own SRDF: give --urdf FILE too, or drop --srdf")
    if args.urdf and args.no_calibrate:
        args.usage_error("--no-calibrate chooses the description of a discovered robot; a "
                         "--urdf description is written as it is: drop one of them")
    folder = check_out_folder(args.out)
    check_package_name(folder.name, args.robot)
    options = TesseractOptions(*args.opw_tolerance)
    if args.urdf:
        (robot, srdf), note = _from_files(args), f"from {args.urdf}"
    else:
        chosen = config_description(args)
        robot, srdf, note = chosen.robot, chosen.description.srdf, chosen.note
    config = tesseract_config(robot.chain, robot.urdf, srdf, folder.name,
                              robot.states.get("home"), options)
    paths = write_tree_atomic(folder, dict(sorted(config.files.items(),
                                                  key=lambda kv: kv[0] == "README.md")))
    others = other_files(folder, paths)
    if others:
        err(report_other_files(folder, others))
    if args.json:
        print_json({"package": config.package, "folder": str(folder),
                    "files": sorted(str(p) for p in paths), "other_files": others,
                    "description": note, "ik_solver": config.solver,
                    "reason": config.reason,
                    "opw": None if config.opw is None else {
                        **{k: getattr(config.opw.parameters, k) for k in (
                            "a1", "a2", "b", "c1", "c2", "c3", "c4", "offsets",
                            "sign_corrections")},
                        "position_error_m": config.opw.position_error_m,
                        "rotation_error_rad": config.opw.rotation_error_rad}})
        return EXIT_OK
    err(config.reason)
    out(f"wrote Tesseract config {config.package} ({len(paths)} files, inverse kinematics "
        f"{config.solver}; description {note}) in {folder}")
    for p in sorted(paths):
        out(f"  {p}")
    return EXIT_OK
