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
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from usar_arm.arm.carry import Carrier
from usar_arm.control.executor import ExecutionOptions, ExecutionReport, Executor
from usar_arm.control.motion import MotionOptions, MotionPlan, plan_motion
from usar_arm.control.tip import TipSensor, platform_sensor_name
from usar_arm.control.tip_correction import correct_tip
from usar_arm.control.tool_accuracy import ToolAccuracy, sensor_accuracy
from usar_arm.control.trajectory import Trajectory
from usar_arm.core.errors import ConnectionLostError, InvalidInputError
from usar_arm.core.fileio import write_tree_atomic
from usar_arm.core.named_file import recorded
from usar_arm.core.spatial import Array, pose_error
from usar_arm.description.cache import cache_folder, robot_from_record
from usar_arm.description.pipeline import DescribeOptions
from usar_arm.discover.interview import discover
from usar_arm.planning.carry_book import CarryBook
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.compiled import warm_up
from usar_arm.planning.ik import IKResult
from usar_arm.planning.robot import Robot, RobotOptions, robot_from_files
from usar_arm.planning.scene import EMPTY, Scene
from usar_arm.planning.scene_file import BUILTIN, load_scene
from usar_arm.urdf.discovery_file import discovery_document, wire_facts
from usar_arm.usarsim.client import UsarClient

log = logging.getLogger("usar_arm.arm.facade")


class TruthReading(Protocol):
    """The simulator's own state of a robot (``usar_arm.sim.truth.Truth``)."""

    @property
    def tool0(self) -> dict[str, Array]:
        """Per actuator, tool0's 4x4 pose in base_link (m)."""


class EmbeddedServer(Protocol):
    """What an arm needs of the embedded simulator it started (``usar_arm.sim.SimServer``);
    typed structurally so that offline use never imports the simulator."""

    @property
    def cell(self) -> str:
        """Its world's work cell (a scene's name or file), or "" when it has none."""

    def truth(self, peer_port: int) -> TruthReading | None:
        """The true state of the robot of the client at ``peer_port``, read under a lock."""

    def stop(self, timeout: float = 10.0) -> None:
        """Stop serving and free the port."""


class Arm(Carrier):
    """A described arm, with (optionally) a live connection to the robot on a server.

    Build one with :meth:`connect` (live) or :meth:`from_files` (offline: plan only).
    """

    def __init__(self, robot: Robot, client: UsarClient | None = None,
                 server: EmbeddedServer | None = None):
        self.robot = robot
        self.client = client
        self.server = server
        self._scenes: dict[str, tuple[Scene, CollisionWorld]] = {}
        self._carry = CarryBook()
        self._mounted = True  # (the tool changer holds its tool: carry.Carrier)
        self._executor: Executor | None = None
        self.cache_entry: Path | None = None
        """The description cache's entry of this arm (connected arms only)."""

    # ------------------------------------------------------------------ construction
    @classmethod
    def connect(cls, robot: str = "KR60", host: str | None = None, port: int = 3000,
                start: str | None = None, timeout: float = 5.0, naming: str = "ros-i",
                wire_precision: str = "udk", sim_speed: float = 1.0,
                velocity_limits: str | None = None, cache: Path | None = None,
                calibrated: bool = True) -> Arm:
        """Spawn ``robot`` on a server and learn it (the description comes from the cache when
        the server described the same arm before).

        Args:
            robot: robot class (``KR60`` = ``USARBot.KR60``).
            host: a USARSim server's address; without it the embedded simulator is started
                in this process (``wire_precision`` and ``sim_speed`` configure it).
            port: the server's TCP port.
            calibrated: use the calibrated description when this arm was calibrated before
                (``usar-arm urdf`` or ``calibrate`` cached it); False: the as-learnt one.
        """
        options = DescribeOptions(robot=robot, host=host, port=port, start=start,
                                  naming=naming, velocity_limits=velocity_limits,
                                  wire_precision=wire_precision, timeout=timeout,
                                  accuracy_samples=0)
        server: EmbeddedServer | None = None
        address = (host or "127.0.0.1", port)
        known: tuple[str, ...] = ()
        if host is None:
            # Imported here, not at the top: offline arms (from_files) never load the simulator.
            from usar_arm.description.embedded import known_classes, start_simulator

            # Load the compiled collision kernels first: linking them from numba's cache makes
            # thousands of short calls that, beside the simulator's busy thread, each wait for
            # the GIL (measured: a 2.6 s first plan instead of 0.1 s).
            warm_up()
            simulator = start_simulator(wire_precision, sim_speed)
            server, known = simulator, known_classes()
            assert simulator.port is not None
            address = ("127.0.0.1", simulator.port)
        client = UsarClient(*address, timeout=timeout)
        try:
            client.connect()
            record = discover(client, options.robot_class, start=start, timeout=timeout,
                              known_classes=known)
            arm = cls(robot_from_record(record, options, cache, calibrated), client, server)
            arm.cache_entry = cache_folder(record, options, cache)
        except BaseException:
            client.close()
            if server is not None:
                server.stop()
            raise
        return arm

    @classmethod
    def from_files(cls, urdf: str | Path, srdf: str | Path | None = None,
                   group: str | None = None, tip: str | None = None, *,
                   base: str | None = None, package_paths: Mapping[str, str] | None = None,
                   convex_hull: bool = False) -> Arm:
        """An offline arm (IK, planning) from any URDF (+ SRDF, joint_limits.yaml beside it); the
        other arguments as :meth:`RobotOptions.of` says (RobotStructureError: no chain to plan)."""
        return cls(robot_from_files(urdf, srdf, options=RobotOptions.of(
            group, base, tip, package_paths, convex_hull)))

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
        """The SRDF's home configuration (without one: each joint at 0, or mid-range)."""
        return np.array(self.robot.home())

    def write_description(self, out_dir: str | Path) -> list[Path]:
        """Write the description's files (URDF, SRDF, joint limits, discovery notes) into
        ``out_dir``, atomically; returns their paths."""
        if not self.robot.files:
            raise InvalidInputError("this arm's description has no files to write")
        return write_tree_atomic(out_dir, self.robot.files)

    def fk(self, q: Array, frame: str = "tool0") -> Array:
        """4x4 pose of ``frame`` in base_link at ``q``."""
        return self.planning_robot.kinematics.frame_pose(np.asarray(q, float), frame)

    # ------------------------------------------------------------------ the live robot
    def joints(self, timeout: float = 2.0, newer_than: float | None = None) -> Array:
        """Current joint values from the latest ASTA (rad/m, configuration order)."""
        client = self._live()
        asta = client.wait_asta(str(self.robot.actuator), after_time=newer_than,
                                timeout=timeout)
        joints = asta.joints(self.robot.wire_links)
        if joints is None:
            missing = list(asta.missing(self.robot.wire_links))
            raise ConnectionLostError("reading joint values",
                                      f"ASTA lacks links {missing}: {asta}")
        return np.array(joints)

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
        else:  # (a Path is a path even when it reads like a shipped name: core/named_file.py)
            key, loaded = f"{type(scene).__name__} {scene}", None
        if key not in self._scenes:
            loaded = loaded or load_scene(scene)  # type: ignore[arg-type]
            self._scenes[key] = (loaded, self.planning_robot.collision_world(
                self._carry.view(loaded)))
        return self._scenes[key][1]

    def ik(self, pose: Array, seed: Array | None = None, all_solutions: bool = False,
           scene: str | Path | Scene | None = None) -> IKResult:
        """IK of tool0 for ``pose``: nearest ``seed``, or every solution."""
        world = self.world(scene) if scene is not None else None
        return self.planning_robot.ik_solver().solve(np.asarray(pose, float), seed,
                                                     all_solutions, world)

    def plan(self, *, joints: Array | None = None, pose: Array | None = None,
             motion: str = "ptp", scene: str | Path | Scene | None = None,
             start: Array | None = None, options: MotionOptions | None = None,
             **overrides: Any) -> MotionPlan:
        """Plan and time a motion to a configuration or a tool0 pose.

        ``start`` defaults to the arm's current joints (live) or home (offline). Keyword
        overrides (``speed_scale=0.3``, ``blend=True``...) change :class:`MotionOptions`. The
        trajectory records a scene given by name or path (``Trajectory.scene``), and what the
        arm carries (:meth:`~usar_arm.arm.carry.Carrier.attach`) in ``info['attached']``.
        """
        opts = replace(options or MotionOptions(), motion=motion, **overrides)
        start = self._here(start)
        plan = self._recorded(plan_motion(
            self.planning_robot, self._carried_world(self.world(scene), start), start,
            goal=None if joints is None else np.asarray(joints, float),
            pose=None if pose is None else np.asarray(pose, float), options=opts))
        if scene is None or isinstance(scene, Scene):
            return plan
        named = recorded(scene, "scene", BUILTIN)  # (so that the trajectory's file says it)
        return replace(plan, trajectory=replace(plan.trajectory, scene=named))

    # ------------------------------------------------------------------ execution
    def executor(self, options: ExecutionOptions | None = None) -> Executor:
        """The executor of this connection (its drive model is identified once and kept)."""
        client = self._live()
        if self._executor is None:
            chain = self.robot.chain
            self._executor = Executor(client, str(self.robot.actuator), self.robot.wire_links,
                                      chain.joint_names, chain.lower(), chain.upper(), options)
        elif options is not None:
            self._executor.options = options
        return self._executor

    def execute(self, trajectory: Trajectory, *, goal_pose: Array | None = None,
                tip_correction: bool = False, options: ExecutionOptions | None = None
                ) -> ExecutionReport:
        """Stream a trajectory to the arm, settle, and measure where tool0 ended up.

        The tool0 error is measured against ``goal_pose`` (default: the model's tool0 at the
        trajectory's end) with the server's tip GroundTruth sensor, or computed from the final
        ASTA values when the server has none. With ``tip_correction`` (a tip sensor is needed)
        the model's tool bias is measured and the joint goal re-solved until the sensor agrees
        that tool0 is within 0.5 mm / 0.5 mrad (:mod:`usar_arm.control.tip_correction`; about
        8 s per move). When the simulator runs in this process, the true error (its physics)
        is reported too.

        Raises:
            ExecutionAbortedError: see :meth:`Executor.execute`.
        """
        executor = self.executor(options)
        sensor = self.tip_sensor()
        if tip_correction and sensor is None:
            raise InvalidInputError(
                "tip correction needs the arm's tip GroundTruth sensor, and the server reports "
                f"none for {self.robot.actuator} (it streams "
                f"{', '.join(self._live().known_components()) or 'no sensors'})")
        report = executor.execute(trajectory)
        target = self.fk(trajectory.q[-1]) if goal_pose is None else np.asarray(goal_pose)
        goal = report.goal
        if sensor is not None:
            reading = sensor.read()
            tip = sensor_accuracy(sensor.source, target, reading.pose, reading.step_m)
            if tip_correction:
                fix = correct_tip(sensor, lambda q: self._sensor_world(sensor, q),
                                  lambda pose, seed: np.array(
                                      self.robot.ik_solver().solve(pose, seed).best.q),
                                  executor.settle, lambda: executor.measure()[0], report.goal,
                                  target, joint_step=self.joint_step())
                goal, tip = fix.goal, fix.applied_to(tip)
        else:
            q, _ = executor.measure()
            _, err_m, err_rad = pose_error(target, self.fk(q))
            tip = ToolAccuracy("forward kinematics of the final ASTA values", err_m, err_rad)
        truth = self._true_tool0()
        if truth is not None:
            _, true_m, true_rad = pose_error(target, truth)
            tip = replace(tip, true_error_m=true_m, true_error_rad=true_rad)
        final, _ = executor.measure()
        return replace(report, tip=tip, goal=goal, final_joint_error_rad=np.abs(final - goal))

    def asta_time(self, timeout: float = 2.0) -> float:
        """The simulated time (s) of the newest ASTA line: readings newer than it were taken
        after everything sent so far."""
        return float(self._live().wait_asta(str(self.robot.actuator), timeout=timeout).time)

    def joint_step(self) -> float:
        """The resolution the server prints joint values with (0 = full precision)."""
        rec = self._live().latest("ASTA", str(self.robot.actuator))
        return rec.step("Value") if rec is not None else 0.0

    def _sensor_world(self, sensor: TipSensor, q: Array) -> Array:
        """The tip sensor frame's world pose (z-down) by the model at ``q``."""
        return sensor.world_from_tool0(self.fk(q))

    def _sensor_to_tool0(self) -> Array:
        """tool0 in the tip sensor's frame.

        The model's offset, except where the sensor sits at the Tip: when the model puts them
        no farther apart than the step the server printed the Tip with (UDK: 0.01 m, so the
        KR60's 0.048 m Tip reads 0.05 while its sensor mount reads 0.048), they are one point
        and the sensor, printed finer, says where it is; only the rotation is kept.
        """
        zero = np.zeros(len(self.joint_names))
        offset = np.linalg.inv(self.fk(zero, str(self.robot.tip_sensor))) @ self.fk(zero)
        step = self.tip_step()
        if step > 0 and float(np.linalg.norm(offset[:3, 3])) <= step:
            offset[:3, 3] = 0.0
        return offset

    def tip_step(self) -> float:
        """The resolution (m) the server printed the Tip with (0: exact or unknown)."""
        doc = discovery_document(self.robot.files)
        return wire_facts(doc).tip_resolution_m if doc is not None else 0.0

    def tip_sensor(self) -> TipSensor | None:
        """The server's tip GroundTruth sensor of this arm (None offline or without one)."""
        sensor = self.robot.tip_sensor
        if self.client is None or not sensor:
            return None
        platform = platform_sensor_name(self.client, sensor)
        if platform is None:
            return None
        return TipSensor(self.client, sensor, platform, self._sensor_to_tool0())

    def _true_tool0(self) -> Array | None:
        """tool0 in base_link as the embedded simulator's own spec and physics have it (None
        with a remote server): read under the server's lock, nothing learnt involved."""
        if self.server is None or self.client is None or self.robot.actuator is None:
            return None
        port = self.client.local_port
        truth = self.server.truth(port) if port is not None else None
        if truth is None:
            return None
        return truth.tool0.get(str(self.robot.actuator))
