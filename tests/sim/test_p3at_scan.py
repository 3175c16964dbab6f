"""The LMS200's ranges against an independent ray cast of the world file.

The reference cast shares no code with the simulator: it reads the shipped world's YAML itself
and intersects each ray with each box in plain numpy (2-D slabs at the scan height), from the
scanner pose that the GroundTruth line reports plus the mount of DefaultUSAR.ini
(X=0.2085, Z=-0.2), with the ray angles stepped as RangeScanner.uc steps them.
"""

from __future__ import annotations

import math
from importlib import resources

import numpy as np
import pytest
import yaml

from tests.sim.p3at_client import spawn_p3at
from usar_arm.usarsim import messages as m

MOUNT = np.array([0.2085, 0.0, -0.2])
MAX_RANGE = 20.0
UU_PER_RAD = 65536 / (2 * math.pi)
TOLERANCE = 0.02
"""Metres: ranges print truncated to 0.01 m, the pose to 1 mm and 1 mrad."""


def ray_angles() -> np.ndarray:
    """RangeScanner.uc: integer Unreal units from int(FOV/2) down to -FOV/2 by Resolution."""
    res, fov = int(0.01745 * UU_PER_RAD), int(3.14159 * UU_PER_RAD)
    return np.arange(fov // 2, -fov / 2 - 1e-9, -res) / UU_PER_RAD


def world_boxes(height: float) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """(centre xy, half xy, yaw) of every box of rooms.yaml that the plane z = height cuts."""
    text = (resources.files("usar_arm.sim") / "worlds" / "rooms.yaml").read_text()
    out = []
    for b in yaml.safe_load(text)["boxes"]:
        c, h = np.array(b["center"], float), np.array(b["half"], float)
        if c[2] - h[2] <= height <= c[2] + h[2]:
            out.append((c[:2], h[:2], float(b.get("yaw", 0.0))))
    return out


def cast(origin: np.ndarray, angle: float, boxes: list[tuple[np.ndarray, np.ndarray, float]]
         ) -> float:
    """Distance from ``origin`` (xy) along heading ``angle`` to the nearest box (slab method)."""
    best = MAX_RANGE
    d = np.array([math.cos(angle), math.sin(angle)])
    for c, h, yaw in boxes:
        rot = np.array([[math.cos(yaw), math.sin(yaw)], [-math.sin(yaw), math.cos(yaw)]])
        o, v = rot @ (origin - c), rot @ d
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = (-h - o) / v, (h - o) / v
        near = np.nanmax(np.where(v == 0, np.where(np.abs(o) <= h, -np.inf, np.inf),
                                  np.minimum(t1, t2)))
        far = np.nanmin(np.where(v == 0, np.where(np.abs(o) <= h, np.inf, -np.inf),
                                 np.maximum(t1, t2)))
        if near <= far and near >= 0:
            best = min(best, float(near))
    return best


@pytest.mark.parametrize("start", ["RobotStart1", "RobotStart2", "RobotStart3"])
def test_ranges_match_an_independent_ray_cast_within_the_resolution(rooms_port: int,
                                                                    start: str) -> None:
    client = spawn_p3at(rooms_port, start, settle_s=1.0)  # at rest on its wheels
    try:
        client.wait_for(lambda line: "{Type RangeScanner}" in line)
        scan = client.latest(m.RangeScan)
        truth = client.latest(m.Sen, "GndTruth")
    finally:
        client.close()
    assert isinstance(scan, m.RangeScan) and isinstance(truth, m.Sen)
    assert truth.location is not None and truth.orientation is not None
    roll, pitch, yaw = truth.orientation
    assert abs(roll) < 0.01 and abs(pitch) < 0.01  # level: the scan plane is horizontal
    c, s = math.cos(yaw), math.sin(yaw)
    origin = np.array(truth.location[:2]) + np.array([[c, -s], [s, c]]) @ MOUNT[:2]
    boxes = world_boxes(truth.location[2] + MOUNT[2])
    angles = ray_angles()
    assert len(scan.ranges) == len(angles) == 181
    half_step = 0.01745 / 2
    misses = []
    for k, (got, a) in enumerate(zip(scan.ranges, angles, strict=True)):
        # Within the resolution: the true range of some ray no further than half a step away.
        around = [cast(origin, yaw + a + da, boxes) for da in (-half_step, 0.0, half_step)]
        if not min(around) - TOLERANCE <= got <= max(around) + TOLERANCE:
            misses.append((k, got, around))
    assert not misses, misses[:5]
    exact = [abs(got - cast(origin, yaw + a, boxes))
             for got, a in zip(scan.ranges, angles, strict=True)]
    assert float(np.median(exact)) < 0.01, float(np.median(exact))
