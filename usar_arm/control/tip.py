"""Where the tool really is: the server's tip GroundTruth sensor, expressed as tool0 in base_link.

The tip sensor reports its world pose and the platform's GroundTruth the robot's, both in the
USARSim z-down world; their relative pose, turned into REP-103, is the sensor frame in
base_link, and the description's fixed sensor -> tool0 transform gives tool0. UDK prints
GroundTruth numbers truncated to 3 decimals: each reading is moved to the middle of the interval
it stands for, which halves the worst-case error (0.5 mm and 0.5 mrad per component).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from usar_arm.core.errors import ResponseTimeoutError
from usar_arm.core.spatial import FLIP_X, Array, invert, rpy_to_matrix, transform
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.numbers import truncated_midpoint


@dataclass(frozen=True)
class RawReading:
    """The tip sensor's world pose as printed (z-down world: location m, roll-pitch-yaw rad),
    the platform's estimated world pose (4x4), the printed steps and the simulated time."""

    location: tuple[float, float, float]
    orientation: tuple[float, float, float]
    platform: Array
    step_m: float
    step_rad: float
    time: float


@dataclass(frozen=True)
class TipReading:
    """tool0 in base_link (4x4) as the sensors saw it, at simulated time ``time`` (s), and the
    step (m, rad) the sensor printed with (0 = full precision)."""

    pose: Array
    time: float
    step_m: float
    step_rad: float


def _pose(client: UsarClient, name: str, after: float | None, timeout: float
          ) -> tuple[Array, float, float, float]:
    rec = client.wait_stream("SEN", name, after_time=after, timeout=timeout)
    sen = rec.message
    assert isinstance(sen, m.Sen), "the SEN stream holds SEN lines"
    step_m, step_rad = rec.step("Location"), rec.step("Orientation")
    if sen.location is None or sen.orientation is None:
        raise ResponseTimeoutError(f"a pose from sensor {name}", timeout,
                                   "its SEN lines carry no Location/Orientation")
    loc = truncated_midpoint(sen.location, step_m)
    rpy = truncated_midpoint(sen.orientation, step_rad)
    return transform(rpy_to_matrix(rpy), loc), float(sen.time or 0.0), step_m, step_rad


class TipSensor:
    """Reads tool0's measured pose from a server's tip and platform GroundTruth sensors.

    Args:
        client: the connection.
        tip_sensor: the tip GroundTruth sensor's name (e.g. KR60ArmTipTruth).
        platform_sensor: the platform's GroundTruth sensor's name (e.g. GroundTruth).
        sensor_to_tool0: 4x4 pose of tool0 in the sensor's frame (from the description).
    """

    def __init__(self, client: UsarClient, tip_sensor: str, platform_sensor: str,
                 sensor_to_tool0: Array):
        self.client = client
        self.tip_sensor = tip_sensor
        self.platform_sensor = platform_sensor
        self.sensor_to_tool0 = np.asarray(sensor_to_tool0, float)
        self._platform = np.eye(4)

    def platform_pose(self) -> Array:
        """The platform's world pose (4x4, z-down) from the last reading, each printed number
        at the middle of its interval."""
        return self._platform.copy()

    @property
    def source(self) -> str:
        """A description for reports."""
        return f"GroundTruth sensor {self.tip_sensor}"

    def read(self, after: float | None = None, timeout: float = 2.0) -> TipReading:
        """The next reading newer than simulated time ``after``, each printed number moved to
        the middle of the interval it stands for."""
        tip, t, step_m, step_rad = _pose(self.client, self.tip_sensor, after, timeout)
        platform, _, _, _ = _pose(self.client, self.platform_sensor, None, timeout)
        self._platform = platform
        return TipReading(self.tool0_from_world(tip), t, step_m, step_rad)

    def read_raw(self, after: float | None = None, timeout: float = 2.0) -> RawReading:
        """The next reading newer than simulated time ``after``, as printed."""
        rec = self.client.wait_stream("SEN", self.tip_sensor, after_time=after, timeout=timeout)
        sen = rec.message
        assert isinstance(sen, m.Sen), "the SEN stream holds SEN lines"
        platform, _, _, _ = _pose(self.client, self.platform_sensor, None, timeout)
        self._platform = platform
        if sen.location is None or sen.orientation is None:
            raise ResponseTimeoutError(f"a pose from sensor {self.tip_sensor}", timeout,
                                       "its SEN lines carry no Location/Orientation")
        return RawReading(sen.location, sen.orientation, platform, rec.step("Location"),
                          rec.step("Orientation"), float(sen.time or 0.0))

    def tool0_from_raw(self, raw: RawReading) -> Array:
        """tool0 in base_link from a raw reading, each number at the middle of its interval."""
        loc = truncated_midpoint(raw.location, raw.step_m)
        rpy = truncated_midpoint(raw.orientation, raw.step_rad)
        return self.tool0_from_world(transform(rpy_to_matrix(rpy), loc))

    def tool0_from_world(self, sensor_world: Array) -> Array:
        """tool0 in base_link from the sensor frame's world pose (z-down)."""
        flip = transform(FLIP_X)
        return flip @ invert(self._platform) @ sensor_world @ flip @ self.sensor_to_tool0

    def world_from_tool0(self, tool0: Array) -> Array:
        """The sensor frame's world pose (z-down) for a tool0 pose in base_link."""
        flip = transform(FLIP_X)
        return self._platform @ flip @ tool0 @ invert(self.sensor_to_tool0) @ flip


def platform_sensor_name(client: UsarClient, tip_sensor: str) -> str | None:
    """The platform's GroundTruth sensor: one the server streams that is not the tip sensor."""
    for comp in client.known_components():
        kind, _, name = comp.partition(" ")
        if kind == "GroundTruth" and name.lower() != tip_sensor.lower():
            return name
    return None
