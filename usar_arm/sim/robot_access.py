"""Reading and commanding the robots of the simulator's world: joint targets and values, the
platform's and the tip's poses, a vehicle's wheels and steering and its scanner's rays, and the
WorldController's teleport of a robot. :class:`~usar_arm.sim.physics.PhysicsWorld` builds and
steps the world; this is its side the sessions talk to about one robot.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from usar_arm.core.spatial import Array, rpy_to_matrix, transform
from usar_arm.sim import mj
from usar_arm.sim.arm_bodies import part_body
from usar_arm.sim.physics_index import ActuatorIndex, RobotEntry
from usar_arm.sim.scenery import quat


class RobotAccess:
    """The robots of a built world, by key (the state :class:`PhysicsWorld` keeps)."""

    _robots: dict[str, RobotEntry]
    _model: mj.Model
    _data: mj.Data
    _spec: mj.Spec

    def _arm(self, key: str, actuator: str) -> ActuatorIndex:
        return self._robots[key].actuators[actuator]

    def set_targets(self, key: str, actuator: str, targets: Sequence[float]) -> None:
        """Set every joint's drive target (rad or m, USARSim sign), clamped to its limits."""
        ctrl = self._data.ctrl
        for (c, sign, low, high), value in zip(self._arm(key, actuator).drives, targets,
                                               strict=True):
            ctrl[c] = sign * min(high, max(low, float(value)))

    def joint_values(self, key: str, actuator: str) -> Array:
        """Measured joint values (rad or m), positive right-handed about each joint's z axis."""
        idx = self._arm(key, actuator)
        return idx.signs * self._data.qpos[idx.qpos_adr]

    def set_joint_values(self, key: str, actuator: str, values: Sequence[float]) -> None:
        """Teleport the joints (and their targets) to ``values``, at rest (for tests)."""
        idx = self._arm(key, actuator)
        v = idx.signs * np.asarray(values, dtype=float)
        self._data.qpos[idx.qpos_adr] = v
        self._data.qvel[idx.dof_adr] = 0.0
        self._data.ctrl[idx.ctrl_idx] = v
        mj.forward(self._model, self._data)

    def joint_anchor(self, key: str, actuator: str, link: int) -> Array:
        """Where joint ``link`` (0-based) of an arm is now (m, z-down world): the origin of
        its child part."""
        act = self._robots[key].actuators[actuator].spec
        body = mj.name_id(self._model, "body",
                          part_body(f"{key}/{actuator}", act.joints[link].child))
        out: Array = self._data.xpos[body].copy()
        return out

    def move_platform(self, key: str, location: Sequence[float], rotation: Sequence[float]
                      ) -> None:
        """Teleport a robot (WorldController AbsMove): a static platform with its arm, or a
        vehicle's chassis (m; roll, pitch, yaw rad; z-down world)."""
        entry = self._robots[key]
        pose = transform(rpy_to_matrix(rotation), location)
        if entry.vehicle is not None:
            qa = self._model.jnt_qposadr[mj.name_id(self._model, "joint",
                                                    f"{entry.vehicle.body}/free")]
            self._data.qpos[qa:qa + 3] = pose[:3, 3]
            self._data.qpos[qa + 3:qa + 7] = quat(pose[:3, :3])
        else:
            entry.location = tuple(float(v) for v in location)
            entry.rotation = tuple(float(v) for v in rotation)
            entry.platform_pose = pose
            body = self._spec.body(f"{key}/platform")
            body.pos, body.quat = list(entry.location), quat(pose[:3, :3])
            b = mj.name_id(self._model, "body", f"{key}/platform")
            self._model.body_pos[b], self._model.body_quat[b] = body.pos, body.quat
        mj.forward(self._model, self._data)

    def platform_pose(self, key: str) -> Array:
        """World pose (4x4) of a robot's platform (a vehicle's chassis where it is now)."""
        entry = self._robots[key]
        if entry.vehicle is None:
            return entry.platform_pose.copy()
        b = entry.vehicle.body_id
        return transform(self._data.xmat[b].reshape(3, 3).copy(), self._data.xpos[b].copy())

    def set_wheel_speeds(self, key: str, speeds: dict[str, float]) -> None:
        """Set the target spin (rad/s, positive forward) of a vehicle's driven wheels."""
        veh = self._robots[key].vehicle
        assert veh is not None, f"{key} is not a vehicle"
        for wheel, speed in speeds.items():
            self._data.ctrl[veh.wheel_ctrl[wheel]] = speed

    def set_steer_targets(self, key: str, targets: dict[str, float]) -> None:
        """Set the target angle (rad, positive turns right) of steer joints by UDK name."""
        veh = self._robots[key].vehicle
        assert veh is not None, f"{key} is not a vehicle"
        for joint, angle in targets.items():
            self._data.ctrl[veh.steer_ctrl[joint]] = angle

    def steer_angles(self, key: str) -> dict[str, float]:
        """The angle (rad, positive turning right) of every steer joint of a vehicle."""
        veh = self._robots[key].vehicle
        assert veh is not None, f"{key} is not a vehicle"
        return {s: float(self._data.qpos[a]) for s, a in veh.steer_qpos.items()}

    def wheel_angles(self, key: str) -> dict[str, float]:
        """The accumulated spin (rad, positive forward) of every wheel of a vehicle."""
        veh = self._robots[key].vehicle
        assert veh is not None, f"{key} is not a vehicle"
        return {w: float(self._data.qpos[a]) for w, a in veh.wheel_qpos.items()}

    def cast_rays(self, key: str, origin: Array, directions: Array, max_range: float) -> Array:
        """Distance (m) along each unit direction (n x 3, world) from ``origin`` to the first
        surface of the world that is not the robot ``key``'s chassis; ``max_range`` where
        nothing is nearer."""
        entry = self._robots[key]
        exclude = entry.vehicle.body_id if entry.vehicle is not None else -1
        dist, geom = mj.multi_ray(self._model, self._data, origin, directions, exclude, max_range)
        return np.where((geom < 0) | (dist < 0) | (dist > max_range), max_range, dist)

    def tip_pose(self, key: str, actuator: str) -> Array:
        """World pose (4x4) of an arm's tip frame."""
        idx = self._arm(key, actuator)
        sid = idx.tip_site_id
        return transform(self._data.site_xmat[sid].reshape(3, 3).copy(),
                         self._data.site_xpos[sid].copy())

    @property
    def robot_keys(self) -> tuple[str, ...]:
        """Keys of the robots in the world."""
        return tuple(self._robots)
