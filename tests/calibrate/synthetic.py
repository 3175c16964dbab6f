"""Synthetic tracker data with a known answer, made without the calibration code: the nominal
KR60 URDF with every joint origin's numbers perturbed in the XML (xml.etree), the truth poses
from Pinocchio on that perturbed URDF, then noise and truncation toward zero."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from usar_arm.calibrate.measurements import Measurement
from usar_arm.core.spatial import Array, matrix_to_rpy
from usar_arm.planning.kinematics import KinematicModel

KR60 = (Path(__file__).resolve().parents[2] / "robots/generated/KR60.urdf").read_text()


def perturbed(urdf: str, seed: int, metres: float = 1e-3, radians: float = 5e-3) -> str:
    """Every joint origin (actuated and fixed) moved by up to ``metres`` per axis and turned by
    up to ``radians`` per roll/pitch/yaw number."""
    rng = np.random.default_rng(seed)
    root = ET.fromstring(urdf)
    for joint in root.findall("joint"):
        origin = joint.find("origin")
        assert origin is not None
        xyz = np.array(origin.get("xyz", "0 0 0").split(), float)
        rpy = np.array(origin.get("rpy", "0 0 0").split(), float)
        xyz += rng.uniform(-metres, metres, 3)
        rpy += rng.uniform(-radians, radians, 3)
        origin.set("xyz", " ".join(repr(float(v)) for v in xyz))
        origin.set("rpy", " ".join(repr(float(v)) for v in rpy))
    return ET.tostring(root, encoding="unicode")


def random_q(model: KinematicModel, count: int, seed: int, margin: float = 0.1) -> Array:
    """Configurations uniform within the limits shrunk by ``margin`` (fraction of the span)."""
    rng = np.random.default_rng(seed)
    lo, hi = model.lower, model.upper
    span = hi - lo
    return rng.uniform(lo + margin * span, hi - margin * span, (count, model.nq))


def truncate(value: float, step: float) -> float:
    """``value`` printed truncated toward zero to ``step``."""
    return float(np.trunc(value / step) * step) if step > 0 else value


def readings(truth_urdf: str, frame: str, base: Array, q: Array, seed: int,
             sigma_m: float = 0.0, sigma_rad: float = 0.0, step_m: float = 0.0,
             step_rad: float = 0.0, state_sigma: bool = True) -> list[Measurement]:
    """Measurements of ``frame`` in M = base * FK_truth(q), noisy then truncated."""
    rng = np.random.default_rng(seed)
    km = KinematicModel(truth_urdf)
    out = []
    for k, qk in enumerate(q):
        pose = base @ km.frame_pose(qk, frame)
        pos = pose[:3, 3] + rng.normal(0, sigma_m, 3) if sigma_m else pose[:3, 3]
        rpy = np.array(matrix_to_rpy(pose[:3, :3])) + (rng.normal(0, sigma_rad, 3)
                                                      if sigma_rad else 0.0)
        out.append(Measurement(
            np.array(qk), np.array([truncate(v, step_m) for v in pos]),
            np.array([truncate(v, step_rad) for v in rpy]), step_m, step_rad,
            sigma_m if state_sigma else 0.0, sigma_rad if state_sigma else 0.0, f"pose {k}"))
    return out


def tool_errors(truth_urdf: str, truth_base: Array, cal_urdf: str, cal_base: Array,
                frame: str, q: Array) -> tuple[float, float]:
    """Max position (m) and rotation (rad) error of ``frame`` in M, calibrated vs truth."""
    a, b = KinematicModel(truth_urdf), KinematicModel(cal_urdf)
    worst_m = worst_rad = 0.0
    for qk in q:
        ta, tb = truth_base @ a.frame_pose(qk, frame), cal_base @ b.frame_pose(qk, frame)
        worst_m = max(worst_m, float(np.linalg.norm(ta[:3, 3] - tb[:3, 3])))
        c = (np.trace(ta[:3, :3].T @ tb[:3, :3]) - 1) / 2
        worst_rad = max(worst_rad, float(np.arccos(np.clip(c, -1, 1))))
    return worst_m, worst_rad
