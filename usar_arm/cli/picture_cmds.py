"""``usar-arm render``, ``plot`` and ``view``: pictures of the arm and of trajectories."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from usar_arm.cli.commands import add_command
from usar_arm.cli.common import add_verbosity, err, out, setup_logging, verbosity
from usar_arm.cli.robot_args import add_robot_args, robot_from_args
from usar_arm.control.trajectory import Trajectory, load_with_executed
from usar_arm.core.errors import EXIT_OK, InvalidInputError
from usar_arm.core.world_file import load_scenery
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import Scene
from usar_arm.planning.scene_file import load_scene


def add_parsers(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    r = add_command(
        sub, "render",
        description="A PNG of the arm's URDF cylinders at --joints (default: home, or the "
                    "trajectory's end), the scene's obstacles, and the tool0 path of "
                    "--trajectory with its start pose as a ghost; or, with --world, a world "
                    "file's top view. Headless (matplotlib).")
    r.add_argument("--joints", type=float, nargs="+", metavar="Q", help="configuration to draw")
    r.add_argument("--scene", default=None, metavar="FILE",
                   help="a scene YAML file, or one of empty, table, shelf, cage (default: "
                        "the scene --trajectory was planned in)")
    r.add_argument("--trajectory", default=None, metavar="TRAJ.json",
                   help="draw its tool0 path (a trajectory from plan --out)")
    r.add_argument("--world", default=None, metavar="FILE|NAME",
                   help="draw this world file (or shipped world: default, rooms) alone, top "
                        "view in metres; no robot is drawn")
    r.add_argument("--out", required=True, metavar="PNG", help="the picture to write")
    r.add_argument("--size", type=int, nargs=2, default=(1000, 800), metavar=("W", "H"),
                   help="pixels (default 1000 800)")
    r.add_argument("--view", type=float, nargs=2, default=(24.0, -58.0),
                   metavar=("ELEV", "AZIM"), help="view angles in degrees (default 24 -58)")
    add_robot_args(r)
    add_verbosity(r)
    r.set_defaults(handler=run_render)

    p = add_command(
        sub, "plot",
        description="Position, velocity, acceleration and jerk of every joint over time, with "
                    "dashed limit lines; executed ASTA samples are overlaid when the file has "
                    "them (execute --out, plan --execute --out).")
    p.add_argument("trajectory", metavar="TRAJ.json")
    p.add_argument("--out", required=True, metavar="PNG", help="the picture to write")
    p.add_argument("--no-jerk", action="store_true", help="leave out the jerk column")
    p.add_argument("--width", type=int, default=1600, help="pixels (default 1600)")
    add_verbosity(p)
    p.set_defaults(handler=run_plot)

    v = add_command(
        sub, "view",
        description="Serve a viser page (open it in a browser) that replays the trajectory on "
                    "the arm's URDF in its scene, with play/pause and a time slider, until "
                    "Ctrl-C; or write a self-contained HTML replay with --html.")
    v.add_argument("trajectory", metavar="TRAJ.json")
    v.add_argument("--scene", default=None, metavar="FILE",
                   help="a scene YAML file, or one of empty, table, shelf, cage (default: "
                        "the scene the trajectory was planned in)")
    v.add_argument("--html", default=None, metavar="FILE",
                   help="write a self-contained HTML replay instead of serving")
    v.add_argument("--bind", default="127.0.0.1", metavar="ADDR",
                   help="address to serve on (default 127.0.0.1)")
    v.add_argument("--http-port", type=int, default=8080, metavar="PORT",
                   help="port to serve on (default 8080; the next free one if taken)")
    add_robot_args(v)
    add_verbosity(v)
    v.set_defaults(handler=run_view)


def _scene(name: str | None, traj: Trajectory | None = None) -> Scene | None:
    """The scene named on the command line, else the one the trajectory was planned in."""
    named = name or (traj.scene if traj is not None else None)
    return load_scene(named) if named else None


def _check_joints(robot: Robot, traj: Trajectory, path: str) -> None:
    if traj.joint_names != robot.chain.joint_names:
        raise InvalidInputError(f"{path}: its joints are {', '.join(traj.joint_names)}, the "
                                f"robot's are {', '.join(robot.chain.joint_names)}")


def run_render(args: argparse.Namespace) -> int:
    from usar_arm.export.render import render_arm, tool_path  # matplotlib: only when drawing

    setup_logging(verbosity(args))
    if min(args.size) < 100:
        raise InvalidInputError(f"--size must be at least 100 x 100 pixels, got {args.size}")
    if args.world is not None:
        return _render_world(args)
    traj = Trajectory.load(args.trajectory) if args.trajectory else None
    scene = _scene(args.scene, traj)
    robot = robot_from_args(args)
    chain = robot.chain
    if args.joints is not None:
        if len(args.joints) != chain.dof:
            raise InvalidInputError(f"--joints needs {chain.dof} values "
                                    f"({', '.join(chain.joint_names)}), got {len(args.joints)}")
        q = np.array(args.joints)
    elif traj is not None:
        q = traj.q[-1]
    else:
        q = np.array(robot.home())
    path, ghosts = None, []
    if traj is not None:
        _check_joints(robot, traj, args.trajectory)
        path = tool_path(chain, traj)
        ghosts = [traj.q[0]]
    render_arm(args.out, chain, q, scene, path, ghosts=ghosts, size=tuple(args.size),
               view=tuple(args.view))
    out(f"wrote {args.out}")
    return EXIT_OK


def _render_world(args: argparse.Namespace) -> int:
    from usar_arm.export.world_plot import render_world  # matplotlib: only when drawing

    scenery = load_scenery(args.world)
    render_world(args.out, scenery, title=Path(args.world).stem, size=tuple(args.size))
    out(f"wrote {args.out} ({len(scenery.boxes)} boxes)")
    return EXIT_OK


def run_plot(args: argparse.Namespace) -> int:
    from usar_arm.export.plot import plot_trajectory  # matplotlib: only when plotting

    setup_logging(verbosity(args))
    traj, executed = load_with_executed(args.trajectory)
    plot_trajectory(args.out, traj, executed, jerk=not args.no_jerk, width=args.width)
    out(f"wrote {args.out}" + (f" ({len(executed.t)} executed samples)" if executed else ""))
    return EXIT_OK


def run_view(args: argparse.Namespace) -> int:
    from usar_arm.export.view import export_html, serve_replay  # optional extra: viser

    setup_logging(verbosity(args))
    traj = Trajectory.load(args.trajectory)
    scene = _scene(args.scene, traj)
    robot = robot_from_args(args)
    _check_joints(robot, traj, args.trajectory)
    if args.html:
        export_html(args.html, robot.urdf, traj, scene)
        out(f"wrote {args.html}")
        return EXIT_OK
    with serve_replay(robot.urdf, traj, scene, host=args.bind, port=args.http_port) as server:
        out(f"replaying {args.trajectory} at {server.url} (Ctrl-C to stop)")
        try:
            server.wait()
        except KeyboardInterrupt:
            err("stopped")
    return EXIT_OK
