"""Joint frames of a learnt arm: accumulated, snapped, and converted to the output frame.

GEO gives each link's Location in the actuator base frame (so anchors add up directly) and its
Orientation relative to the parent joint (so rotations multiply down the chain). Over a UDK wire
orientations arrive rounded to 0.01 rad, so accumulated axes drift by up to a few hundredths of a
radian; axes and frames within ``snap_tolerance`` of a canonical direction (±x, ±y, ±z) are
snapped, as the 2012 "perp" variant did, and every snap is reported.

The one conversion from the USARSim z-down frame to REP-103 z-up happens in :func:`to_frame`.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from usar_arm.core.spatial import (
    FLIP_X,
    Array,
    angle_between,
    rotation_distance,
    rpy_to_matrix,
    transform,
    zdown_to_zup_point,
    zdown_to_zup_rotation,
)
from usar_arm.discover.wire_arm import WireArm

SNAP_FACTOR = 2.5
"""Snap tolerance as a multiple of the printed orientation resolution: each relative rotation
is off by at most ~0.87 resolution (three components rounded by half a step each), and each
frame is snapped before the next builds on it, so errors do not add up along the chain."""


def _canonical_rotations() -> list[Array]:
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            r = np.zeros((3, 3))
            for row, col in enumerate(perm):
                r[row, col] = signs[row]
            if np.linalg.det(r) > 0:
                out.append(r)
    return out


CANONICAL_ROTATIONS = _canonical_rotations()
CANONICAL_AXES = [np.array(v, dtype=float) for v in
                  ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))]


@dataclass(frozen=True)
class Snap:
    """One snapped quantity: what, and by how much it moved (rad)."""

    what: str
    deviation_rad: float
    to: tuple[float, ...]


@dataclass(frozen=True)
class ArmFrames:
    """Anchors, rotations and axes of every joint, plus mount, tip and tip sensor.

    Positions are in metres, in the actuator base frame (``frame`` says which convention: z-up
    REP-103 or the USARSim z-down frame). ``mount`` is the 4x4 pose of the actuator frame in the
    platform frame.
    """

    frame: str
    anchors: tuple[Array, ...]
    rotations: tuple[Array, ...]
    axes: tuple[Array, ...]
    mount: Array
    tip: Array
    tip_sensor: Array | None
    snaps: tuple[Snap, ...]


def nearest_axis(v: Array) -> tuple[Array, float]:
    """The canonical axis nearest to ``v`` and the angle to it (rad)."""
    best = min(CANONICAL_AXES, key=lambda a: angle_between(a, v))
    return best, angle_between(best, v)


def nearest_rotation(r: Array) -> tuple[Array, float]:
    """The canonical (axis-permuting) rotation nearest to ``r`` and the angle to it (rad)."""
    best = min(CANONICAL_ROTATIONS, key=lambda c: rotation_distance(c, r))
    return best, rotation_distance(best, r)


def snap_tolerance_for(arm: WireArm) -> float:
    """The deviation (rad) the wire's rounding can explain: 2.5 x the printed orientation step
    (0.025 rad over a UDK wire; 0 when numbers arrive at full precision)."""
    return SNAP_FACTOR * arm.orientation_resolution


def accumulate(arm: WireArm, snap_tolerance: float | None = None) -> ArmFrames:
    """Joint frames in the USARSim z-down actuator frame, with near-canonical ones snapped.

    ``snap_tolerance`` (rad) defaults to what the wire's printed resolution can explain
    (:func:`snap_tolerance_for`). A joint whose whole frame is within tolerance of a canonical
    rotation is snapped to it, so its axis is exact and later joints build on the exact frame;
    otherwise only its axis is snapped when close to canonical, and its frame is kept as sent.
    """
    if snap_tolerance is None:
        snap_tolerance = snap_tolerance_for(arm)
    anchors, rotations, axes, snaps = [], [], [], []
    pos, rot = np.zeros(3), np.eye(3)
    by_link: dict[int, tuple[Array, Array]] = {0: (pos, rot)}
    for jt in arm.joints:
        ppos, prot = by_link[jt.parent]
        pos = ppos + np.asarray(jt.location, dtype=float)
        rot = prot @ rpy_to_matrix(jt.orientation)
        canon, dev = nearest_rotation(rot)
        if 0 < dev <= snap_tolerance:
            snaps.append(Snap(f"link {jt.link} frame", dev, tuple(canon.ravel())))
            rot = canon
        axis = rot[:, 2].copy()
        if dev > snap_tolerance:
            canon_axis, adev = nearest_axis(axis)
            if 0 < adev <= snap_tolerance:
                snaps.append(Snap(f"link {jt.link} axis", adev, tuple(canon_axis)))
                axis = canon_axis
        by_link[jt.link] = (pos, rot)
        anchors.append(pos)
        rotations.append(rot)
        axes.append(axis)
    mount_rot = rpy_to_matrix(arm.mount_orientation)
    canon, dev = nearest_rotation(mount_rot)
    if 0 < dev <= snap_tolerance:
        snaps.append(Snap("actuator mount", dev, tuple(canon.ravel())))
        mount_rot = canon
    tip = anchors[-1] + np.asarray(arm.tip, dtype=float)
    sensor = None
    if arm.tip_sensor is not None and 1 <= arm.tip_sensor.link <= len(arm.joints):
        k = [j.link for j in arm.joints].index(arm.tip_sensor.link)
        srot = rotations[k] @ rpy_to_matrix(arm.tip_sensor.orientation)
        canon, dev = nearest_rotation(srot)
        if 0 < dev <= snap_tolerance:
            snaps.append(Snap(f"sensor {arm.tip_sensor.name} frame", dev, tuple(canon.ravel())))
            srot = canon
        sensor = transform(srot, anchors[k] + np.asarray(arm.tip_sensor.location, dtype=float))
    return ArmFrames("z-down", tuple(anchors), tuple(rotations), tuple(axes),
                     transform(mount_rot, arm.mount_location), tip, sensor, tuple(snaps))


def to_frame(frames: ArmFrames, frame: str) -> ArmFrames:
    """The frames in the output convention: ``z-up`` (REP-103, default) or ``z-down`` (2012).

    This is the single place where the USARSim z-down frame becomes REP-103's z-up one:
    (x, y, z) -> (x, -y, -z) and R -> Rx(pi) R Rx(pi).
    """
    if frame == frames.frame:
        return frames
    if (frames.frame, frame) != ("z-down", "z-up"):
        raise ValueError(f"unknown frame conversion {frames.frame} -> {frame}")
    flip = transform(FLIP_X)
    return ArmFrames(
        frame="z-up",
        anchors=tuple(zdown_to_zup_point(p) for p in frames.anchors),
        rotations=tuple(zdown_to_zup_rotation(r) for r in frames.rotations),
        axes=tuple(FLIP_X @ a for a in frames.axes),
        mount=flip @ frames.mount @ flip,
        tip=zdown_to_zup_point(frames.tip),
        tip_sensor=None if frames.tip_sensor is None else flip @ frames.tip_sensor @ flip,
        snaps=frames.snaps,
    )
