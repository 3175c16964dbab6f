"""The sensors of a ground vehicle, computed as their UDK classes compute them.

* GroundTruth (GroundTruth.uc, FixedToPlatform): the chassis pose in the world.
* INS (INS.uc): an estimate that integrates the chassis' changes of position and of roll, pitch,
  yaw since the sensor started, each change scaled by ``1 + gaussRand(mean, Sigma)``; UDK's
  ``gaussRand`` returns 0 when Sigma is 0, which is the shipped setting, so the shipped INS does
  not drift. It starts at its own mount's world pose and begins integrating at the first sample
  in which the chassis did not turn (UDK: "go" once the rotation rates are all zero).
* Odometry (Odometry.uc): x, y, theta integrated from the front wheels' spin, with UDK's
  formulas (``thetaVel = r (left - right) / (2 * right front wheel's y)``), from zero.
* RangeScanner (RangeScanner.uc / SICK.uc): one ray per step of Resolution across FOV, right to
  left, from the scanner's mount, the distance to the first surface (MaxRange when none).

The sensors sample on the simulator's 0.1 s status tick; a sensor whose ScanInterval is k ticks
reports every k-th tick. Random numbers come from a generator seeded per robot.
"""

from __future__ import annotations

import math

import numpy as np

from usar_arm.core.spatial import Array, matrix_to_rpy, rpy_to_matrix
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.vehicle import SensorMount, VehicleSpec, scan_yaws
from usar_arm.usarsim import messages as m

TICK_S = 0.1
"""Seconds between the simulator's status ticks (StatusTimer)."""
STILL_RAD = 1e-6
"""A change of roll, pitch and yaw below this (rad per sample) counts as "not turning" for the
INS's start (UDK compares with exactly zero; a settling rigid body in MuJoCo is never exact)."""
TWO_PI = 2.0 * math.pi


def norm_2pi(a: float) -> float:
    """An angle in [0, 2 pi) (``UnitsConverter.normRad_ZeroTo2PI``)."""
    out = math.fmod(a, TWO_PI)
    if out < 0:
        out += TWO_PI
    return 0.0 if out >= TWO_PI else out  # -1e-17 + 2 pi rounds to 2 pi


def diff_angle(a: float, b: float) -> float:
    """The signed difference a - b wrapped into (-pi, pi] (``UnitsConverter.diffAngle``)."""
    d = norm_2pi(a) - norm_2pi(b)
    if d >= math.pi:
        return -(math.pi - math.fmod(d, math.pi))
    if d <= -math.pi:
        return math.pi - math.fmod(abs(d), math.pi)
    return d


def every(mount: SensorMount, default: float) -> int:
    """The number of status ticks between two readings of a sensor (at least 1)."""
    return max(1, round(mount.setting("ScanInterval", default) / TICK_S))


class Ins:
    """The state of one INS (INS.uc)."""

    def __init__(self, mount: SensorMount, rng: np.random.Generator):
        self.mount = mount
        self.rng = rng
        self.sigma = mount.setting("Sigma", 0.0)
        precision = mount.setting("Precision", 1000.0)
        if mount.setting("Drifting", 0.0):
            self.means = (rng.random(6) - 0.5) / np.array([precision**2] * 3 + [precision] * 3)
        else:
            self.means = np.zeros(6)
        self.est: Array | None = None
        self.prev: Array | None = None
        self.go = False

    def set_pose(self, values: list[float]) -> None:
        """``SET {Type INS} {Opcode POSE} {Params x,y,z,r,p,y}``: a new estimate, no drift."""
        self.est = np.asarray(values, dtype=float)
        self.means = np.zeros(6)
        self.go = True

    def _gauss(self, mean: float) -> float:
        return 0.0 if self.sigma == 0 else float(mean + self.sigma * self.rng.standard_normal())

    def read(self, pose: Array) -> m.Ins:
        """One reading at the chassis pose ``pose`` (4x4, world)."""
        rot = np.array(matrix_to_rpy(pose[:3, :3]))
        xyz = pose[:3, 3].copy()
        if self.est is None or self.prev is None:  # AttachItem: the sensor's own pose
            mount = pose[:3, :3] @ np.asarray(self.mount.position) + xyz
            own = matrix_to_rpy(pose[:3, :3] @ rpy_to_matrix(self.mount.direction))
            self.est = np.array([*mount, *(norm_2pi(a) for a in own)])
            self.prev = np.concatenate([xyz, rot])
        rate = [diff_angle(rot[i], self.prev[3 + i]) for i in range(3)]
        if self.go:
            for i in range(3):
                self.est[3 + i] = norm_2pi(self.est[3 + i] + rate[i]
                                           + rate[i] * self._gauss(self.means[i]))
            delta = xyz - self.prev[:3]
            dist = float(np.linalg.norm(delta))
            for i in range(3):
                self.est[i] += delta[i] + dist * self._gauss(self.means[3 + i])
        elif all(abs(r) < STILL_RAD for r in rate):
            self.go = True
        self.prev = np.concatenate([xyz, rot])
        e = self.est
        return m.Ins(self.mount.name, (float(e[0]), float(e[1]), float(e[2])),
                     (float(e[3]), float(e[4]), float(e[5])))


class Odometry:
    """The state of one odometry sensor (Odometry.uc)."""

    def __init__(self, mount: SensorMount, spec: VehicleSpec):
        self.mount = mount
        self.left, self.right = (w.name for w in spec.front_wheels())
        self.radius = spec.wheel_radius
        self.l_dist = spec.front_wheels()[1].offset[1] * 2
        self.old: tuple[float, float, float] | None = None
        self.x = self.y = self.theta = 0.0

    def reset(self) -> None:
        """``SET {Type Odometry} {Opcode RESET}``: the pose back to zero."""
        self.x = self.y = self.theta = 0.0

    def read(self, t: float, wheels: dict[str, float]) -> m.Odometry | None:
        """One reading at time ``t`` (s) with the wheels' spin (rad); None right after start."""
        left, right = wheels[self.left], wheels[self.right]
        if self.old is None:
            self.old = (t, left, right)
            return None
        dt = t - self.old[0]
        if dt < 1e-6:
            return None
        left_spin, right_spin = (left - self.old[1]) / dt, (right - self.old[2]) / dt
        self.old = (t, left, right)
        v = self.radius * (right_spin + left_spin) / 2
        self.x += math.cos(self.theta) * v * dt
        self.y += math.sin(self.theta) * v * dt
        self.theta += self.radius * (left_spin - right_spin) / self.l_dist * dt
        return m.Odometry(self.mount.name, (self.x, self.y, self.theta), t)


class Scanner:
    """One range scanner (RangeScanner.uc with SICK.uc's trace)."""

    def __init__(self, mount: SensorMount):
        self.mount = mount
        self.max_range = mount.setting("MaxRange", 4.0)
        yaws, self.resolution, self.fov = scan_yaws(mount.setting("Resolution", 0.157),
                                                     mount.setting("ScanFov", 3.14))
        self.rays = np.stack([np.cos(yaws), np.sin(yaws), np.zeros_like(yaws)], axis=1)
        self.frame = rpy_to_matrix(mount.direction)

    def read(self, t: float, world: PhysicsWorld, key: str, pose: Array) -> m.RangeScan:
        """One scan from the chassis pose ``pose`` (4x4, world)."""
        rot = pose[:3, :3] @ self.frame
        origin = pose[:3, :3] @ np.asarray(self.mount.position) + pose[:3, 3]
        ranges = world.cast_rays(key, origin, self.rays @ rot.T, self.max_range)
        return m.RangeScan(self.mount.name, self.resolution, self.fov,
                           tuple(float(r) for r in ranges), t)


class VehicleSensors:
    """Every sensor of one spawned vehicle, read on the status tick.

    Args:
        spec: the vehicle.
        seed: seeds the random numbers of the noisy sensors.
    """

    def __init__(self, spec: VehicleSpec, seed: int):
        rng = np.random.default_rng(seed)
        self.spec = spec
        self.tick = 0
        self.truths = [(s, every(s, 0.1)) for s in spec.sensors_of("GroundTruth")]
        self.ins = [(Ins(s, rng), every(s, 0.2)) for s in spec.sensors_of("INS")]
        self.odometry = [(Odometry(s, spec), every(s, 0.1)) for s in spec.sensors_of("Odometry")]
        self.scanners = [(Scanner(s), every(s, 0.2)) for s in spec.sensors_of("RangeScanner")]

    def command(self, type_: str, name: str, opcode: str, params: str | None) -> str | None:
        """Act on ``SET {Type type_} {Name name} {Opcode opcode} [{Params params}]`` as the
        sensors' ``Set`` do (Odometry RESET, INS POSE x,y,z,r,p,y); what went wrong, or None.
        UDK sends no reply either way."""
        wanted = type_.upper()
        targets: list[Ins | Odometry] = [
            s for s, _ in (self.ins if wanted == "INS" else self.odometry
                           if wanted == "ODOMETRY" else [])
            if name == "" or s.mount.name.upper() == name.upper()]
        if not targets:
            return f"no {type_} sensor named '{name}' with a SET this simulator supports"
        for sensor in targets:
            if isinstance(sensor, Odometry) and opcode.upper() == "RESET":
                sensor.reset()
            elif isinstance(sensor, Ins) and opcode.upper() == "POSE":
                try:
                    values = [float(v) for v in (params or "").split(",")]
                except ValueError:
                    values = []
                if len(values) != 6 or not all(math.isfinite(v) for v in values):
                    return f"INS POSE needs {{Params x,y,z,roll,pitch,yaw}}, got {params!r}"
                sensor.set_pose(values)
            else:
                return f"{type_} has no opcode {opcode!r} (Odometry: RESET; INS: POSE)"
        return None

    def read(self, t: float, world: PhysicsWorld, key: str) -> list[m.Message]:
        """The SEN messages due at this tick (time ``t``, s)."""
        tick, self.tick = self.tick, self.tick + 1
        pose = world.platform_pose(key)
        out: list[m.Message] = []
        p = pose[:3, 3]
        for mount, k in self.truths:
            if tick % k == 0:
                out.append(m.Sen("GroundTruth", mount.name, t,
                                 (float(p[0]), float(p[1]), float(p[2])),
                                 matrix_to_rpy(pose[:3, :3])))
        for ins, k in self.ins:
            if tick % k == 0:
                out.append(ins.read(pose))
        wheels = world.wheel_angles(key) if self.odometry else {}
        for odo, k in self.odometry:
            reading = odo.read(t, wheels) if tick % k == 0 else None
            if reading is not None:
                out.append(reading)
        for scanner, k in self.scanners:
            if tick % k == 0:
                out.append(scanner.read(t, world, key, pose))
        return out
