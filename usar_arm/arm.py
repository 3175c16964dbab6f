"""``usar_arm.Arm``: one small facade for arm clients.

Connect to a USARSim server (the embedded simulator unless a host is given), spawn and learn the
robot, read its joints, solve IK, plan PTP/LIN motions in a scene, execute them, and write bags
and pictures. Every ``usar-arm`` command is a thin layer over it::

    from usar_arm import Arm

    with Arm.connect("KR60") as arm:              # embedded simulator, discovery, description
        plan = arm.plan(pose=arm.fk(arm.home), scene="table")
        report = arm.execute(plan.trajectory)

Units: m, rad, s; poses are 4x4 transforms of tool0 in base_link.
"""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.discover.session import discover
from usar_arm.errors import ConnectionLostError, InvalidInputError
from usar_arm.motion import MotionOptions, MotionPlan, plan_motion
from usar_arm.pipeline import DescribeOptions
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ik import IKResult
from usar_arm.planning.scene import EMPTY, Scene
from usar_arm.planning.scene_file import load_scene
from usar_arm.robot import Robot, robot_from_files, robot_from_record
from usar_arm.sim.robot_spec import builtin_robots
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.spatial import Array
from usar_arm.usarsim.client import UsarClient

log = logging.getLogger("usar_arm.arm")


class Arm:
    """A described arm, with (optionally) a live connection to the robot on a server.

    Build one with :meth:`connect` (live) or :meth:`from_files` (offline: plan only).
    """

    def __init__(self, robot: Robot, client: UsarClient | None = None,
                 server: SimServer | None = None):
        self.robot = robot
        self.client = client
        self.server = server
        self._scenes: dict[str, tuple[Scene, CollisionWorld]] = {}

    # ------------------------------------------------------------------ construction
    @classmethod
    def connect(cls, robot: str = "KR60", host: str | None = None, port: int = 3000,
                start: str | None = None, timeout: float = 5.0, naming: str = "ros-i",
                wire_precision: str = "udk", sim_speed: float = 1.0,
                velocity_limits: str | None = None, cache: Path | None = None) -> Arm:
        """Spawn ``robot`` on a server and learn it (the description comes from the cache when
        the server described the same arm before).

        Args:
            robot: robot class (``KR60`` = ``USARBot.KR60``).
            host, port: a USARSim server; without ``host`` the embedded simulator is started
                in this process (``wire_precision`` and ``sim_speed`` configure it).
        """
        options = DescribeOptions(robot=robot, host=host, port=port, start=start,
                                  naming=naming, velocity_limits=velocity_limits,
                                  wire_precision=wire_precision, timeout=timeout,
                                  accuracy_samples=0)
        server = None
        address = (host or "127.0.0.1", port)
        if host is None:
            server = SimServer(SimOptions(host="127.0.0.1", port=0,
                                          wire_precision=wire_precision, speed=sim_speed))
            address = ("127.0.0.1", server.start())
        client = UsarClient(*address, timeout=timeout)
        try:
            client.connect()
            record = discover(client, options.robot_class, start=start, timeout=timeout,
                              known_classes=tuple(sorted(builtin_robots())) if server else ())
            arm = cls(robot_from_record(record, options, cache), client, server)
        except BaseException:
            client.close()
            if server is not None:
                server.stop()
            raise
        return arm

    @classmethod
    def from_files(cls, urdf: str | Path, srdf: str | Path | None = None) -> Arm:
        """An offline arm from a URDF (+ SRDF, joint_limits.yaml beside it): IK and planning,
        no execution."""
        return cls(robot_from_files(urdf, srdf))

    def close(self) -> None:
        """Close the connection (the server destroys the robot) and stop an embedded
        simulator."""
        if self.client is not None:
            self.client.close()
            self.client = None
        if self.server is not None:
            self.server.stop()
            self.server = None

    def __enter__(self) -> Arm:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ the description
    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names, in configuration order."""
        return self.robot.chain.joint_names

    @property
    def urdf(self) -> str:
        """The URDF text."""
        return self.robot.urdf

    @property
    def home(self) -> Array:
        """The SRDF's home configuration."""
        return np.array(self.robot.named_state("home"))

    def fk(self, q: Array, frame: str = "tool0") -> Array:
        """4x4 pose of ``frame`` in base_link at ``q``."""
        return self.robot.kinematics.frame_pose(np.asarray(q, float), frame)

    # ------------------------------------------------------------------ the live robot
    def joints(self, timeout: float = 2.0, newer_than: float | None = None) -> Array:
        """Current joint values from the latest ASTA (rad/m, configuration order)."""
        client = self._live()
        asta = client.wait_asta(str(self.robot.actuator), after_time=newer_than,
                                timeout=timeout)
        values = dict(asta.values)
        missing = [k for k in self.robot.links if k not in values]
        if missing:
            raise ConnectionLostError("reading joint values",
                                      f"ASTA lacks links {missing}: {asta}")
        return np.array([values[k] for k in self.robot.links])

    def _live(self) -> UsarClient:
        if self.client is None:
            raise InvalidInputError("this Arm has no connection to a server (it was built from "
                                    "files); use Arm.connect() to move a robot")
        return self.client

    # ------------------------------------------------------------------ scenes, IK, plans
    def world(self, scene: str | Path | Scene | None = None) -> CollisionWorld:
        """The collision world of a scene (a YAML path, a shipped scene name, a Scene)."""
        if scene is None:
            key, loaded = "", EMPTY
        elif isinstance(scene, Scene):
            key, loaded = f"<scene {id(scene)}>", scene
        else:
            key, loaded = str(scene), None
        if key not in self._scenes:
            loaded = loaded or load_scene(str(scene))
            self._scenes[key] = (loaded, self.robot.collision_world(loaded))
        return self._scenes[key][1]

    def ik(self, pose: Array, seed: Array | None = None, all_solutions: bool = False,
           scene: str | Path | Scene | None = None) -> IKResult:
        """IK of tool0 for ``pose``: nearest ``seed``, or every solution."""
        world = self.world(scene) if scene is not None else None
        return self.robot.ik_solver().solve(np.asarray(pose, float), seed, all_solutions,
                                            world)

    def plan(self, *, joints: Array | None = None, pose: Array | None = None,
             motion: str = "ptp", scene: str | Path | Scene | None = None,
             start: Array | None = None, options: MotionOptions | None = None,
             **overrides: Any) -> MotionPlan:
        """Plan and time a motion to a configuration or a tool0 pose.

        ``start`` defaults to the arm's current joints (live) or home (offline). Keyword
        overrides (``speed_scale=0.3``, ``blend=True``...) change :class:`MotionOptions`.
        """
        opts = replace(options or MotionOptions(), motion=motion, **overrides)
        if start is None:
            start = self.joints() if self.client is not None else self.home
        return plan_motion(self.robot, self.world(scene), np.asarray(start, float),
                           goal=None if joints is None else np.asarray(joints, float),
                           pose=None if pose is None else np.asarray(pose, float),
                           options=opts)
