"""The frame bookkeeping around a fit of a tour's readings (:mod:`usar_arm.arm.tour_calibration`).

The tip sensor's readings are its pose in USARSim's z-down world with USARSim's axes, so the
fit runs on the URDF with the sensor's frame turned by pi about x (:func:`usarsim_axes`, done
and undone). The fitted base is moved into the first joint's origin (:func:`fold_base`), and a
sensor at the Tip carries the flange and tool0 with it (:func:`tip_onto_sensor`).
"""

from __future__ import annotations

import numpy as np

from usar_arm.calibrate.parameters import replace_origin
from usar_arm.core.errors import CalibrationError
from usar_arm.core.spatial import FLIP_X, Array, transform
from usar_arm.urdf.description_reader import parse_urdf

FLIP = transform(FLIP_X)
"""A turn of pi about x (4x4): REP-103 axes to USARSim's and back."""


def usarsim_axes(urdf: str, joint: str, turn: Array) -> str:
    """``urdf`` with the fixed joint ``joint``'s origin turned by ``turn`` (4x4, right)."""
    chain, _ = parse_urdf(urdf)
    j = chain.joint(joint)
    return replace_origin(urdf, j, j.origin.matrix() @ turn)


def fold_base(urdf: str, correction: Array) -> str:
    """``urdf`` with the fitted base correction (4x4, base_link before -> after) moved into
    the first joint's origin. base_link is where the platform's GroundTruth puts the arm; the
    fit finds where the chain really starts in the world, which the first joint's frame cannot
    tell apart from the base (its origin parameters are unidentifiable beside the base's)."""
    chain, _ = parse_urdf(urdf)
    first = next(j for j in chain.joints if j.actuated)
    if first.parent != chain.root:
        raise CalibrationError(f"the first joint '{first.name}' does not hang from the root "
                               f"'{chain.root}': cannot move the base correction into it")
    return replace_origin(urdf, first, correction @ first.origin.matrix())


def tip_onto_sensor(calibrated: str, learnt: str, tip_joint: str, mount_joint: str) -> str:
    """``calibrated`` with the Tip joint (which carries the flange and tool0) moved onto the
    calibrated sensor frame: its position, and its rotation turned as the sensor's was (the
    sensor sits at the Tip, so the fit's turn of the sensor frame is the Tip's)."""
    after, _ = parse_urdf(calibrated)
    before, _ = parse_urdf(learnt)
    mount_after = after.joint(mount_joint).origin.matrix()
    mount_before = before.joint(mount_joint).origin.matrix()
    tip = before.joint(tip_joint)
    pose = mount_after @ np.linalg.inv(mount_before) @ tip.origin.matrix()
    pose[:3, 3] = mount_after[:3, 3]
    return replace_origin(calibrated, after.joint(tip_joint), pose)


def mount_joint(urdf: str, frame: str) -> str:
    chain, _ = parse_urdf(urdf)
    for j in chain.joints:
        if j.child == frame and not j.actuated:
            return j.name
    raise CalibrationError(f"the measured frame '{frame}' hangs from no fixed joint in the URDF")


def tip_joint(urdf: str, frame: str, tip_step: float) -> tuple[str | None, str]:
    """The fixed joint that carries the flange when the sensor sits at the Tip, and a sentence
    saying what fixes the tool point."""
    chain, _ = parse_urdf(urdf)
    zero = np.zeros(chain.dof)
    gap = float(np.linalg.norm(chain.frame_pose("flange", zero)[:3, 3]
                               - chain.frame_pose(frame, zero)[:3, 3]))
    sensor_parent = next(j.parent for j in chain.joints if j.child == frame)
    flange = next((j for j in chain.joints if j.child == "flange"), None)
    if flange is not None and flange.parent == sensor_parent and tip_step > 0 \
            and gap <= tip_step:
        return flange.name, (
            f"the tip sensor {frame} sits at the Tip (the printed Tip, {tip_step * 1e3:.0f} mm "
            f"steps, is {gap * 1e3:.1f} mm from it): the flange and tool0 are put on the "
            "calibrated sensor point, so the Tip is identified through the sensor")
    return None, (
        f"the tip sensor {frame} is {gap * 1e3:.1f} mm from the printed Tip: the sensor-to-Tip "
        "offset is not observable from its readings, so the printed Tip offset (step "
        f"{tip_step * 1e3:.0f} mm) stays the only source of the tool point")
