"""Where each robot lives in the compiled MuJoCo model: the bookkeeping of
:class:`usar_arm.sim.physics.PhysicsWorld` (names, and the addresses found after each rebuild)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.sim.robot_spec import ActuatorSpec, RobotSpec
from usar_arm.sim.vehicle import VehicleSpec


@dataclass
class ActuatorIndex:
    """An arm's joints and drives: names, and their qpos/dof/ctrl addresses in the model."""

    spec: ActuatorSpec
    joint_names: list[str]
    actuator_names: list[str]
    signs: Array
    qpos_adr: Array = field(default_factory=lambda: np.zeros(0, dtype=int))
    dof_adr: Array = field(default_factory=lambda: np.zeros(0, dtype=int))
    ctrl_idx: Array = field(default_factory=lambda: np.zeros(0, dtype=int))
    tip_site: str = ""
    tip_site_id: int = -1
    drives: list[tuple[int, float, float, float]] = field(default_factory=list)
    """Per joint: ctrl index, sign, low and high limit (USARSim sign), for :meth:`set_targets`."""
    changer_sites: dict[str, str] = field(default_factory=dict)
    """Tool changer name -> the site at its frame."""


@dataclass
class VehicleIndex:
    """A vehicle's chassis body, wheels and steer joints: names, and their addresses in the
    model."""

    spec: VehicleSpec
    body: str
    wheel_joints: dict[str, str]
    """Wheel name -> joint name."""
    steer_joints: dict[str, str] = field(default_factory=dict)
    """Steer joint name (UDK's, e.g. ``FRFrontSteer``) -> MuJoCo joint name."""
    body_id: int = -1
    wheel_qpos: dict[str, int] = field(default_factory=dict)
    wheel_ctrl: dict[str, int] = field(default_factory=dict)
    steer_qpos: dict[str, int] = field(default_factory=dict)
    steer_ctrl: dict[str, int] = field(default_factory=dict)


@dataclass
class RobotEntry:
    """One robot in the world: its spec, spawn pose (m, rad; 4x4) and indices."""

    key: str
    spec: RobotSpec
    location: tuple[float, ...]
    rotation: tuple[float, ...]
    platform_pose: Array
    actuators: dict[str, ActuatorIndex]
    vehicle: VehicleIndex | None = None
    name: str = ""
    """The robot's name (INIT's Name), for contact reports."""
