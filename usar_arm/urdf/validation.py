"""Checks a generated description must pass before anything is written.

* structure, with ``check_urdf`` (urdfdom's own parser; it ships with cmeel-urdfdom, which ``pin``
  installs) and with yourdfpy;
* semantics, which check_urdf does not look at (docs/conventions.md section 2): lower < upper,
  velocity > 0, effort >= 0, unique names, one root, unit axes, no inertial on the root, REP-199
  frames present and free of geometry, every visible link with a material.

Every problem is collected and reported at once, each naming the joint or link and the rule.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from usar_arm.core.errors import ValidationError
from usar_arm.core.model import KinematicChain
from usar_arm.core.shapes import CylinderShape

REQUIRED_FRAMES = ("base_link", "base", "flange", "tool0")


def semantic_problems(chain: KinematicChain) -> list[str]:
    """Every rule of docs/conventions.md section 2 that ``chain`` breaks."""
    problems = []
    link_names = [lk.name for lk in chain.links]
    joint_names = [j.name for j in chain.joints]
    for kind, names in (("link", link_names), ("joint", joint_names)):
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            problems.append(f"{kind} names must be unique: {', '.join(dupes)} repeated")
    known = set(link_names)
    for j in chain.joints:
        for role in ("parent", "child"):
            if getattr(j, role) not in known:
                problems.append(f"joint {j.name}: {role} link '{getattr(j, role)}' does not exist")
    children = [j.child for j in chain.joints]
    roots = [n for n in link_names if n not in children]
    if len(roots) != 1:
        problems.append(f"exactly one root link is required, found {roots}")
    for n in sorted({c for c in children if children.count(c) > 1}):
        problems.append(f"link {n} is the child of several joints")
    for j in chain.actuated_joints:
        lim = j.limits
        if lim is None:
            problems.append(f"joint {j.name}: a {j.type.value} joint needs <limit>")
            continue
        if not lim.lower < lim.upper:
            problems.append(f"joint {j.name}: lower limit {lim.lower} must be below upper "
                            f"{lim.upper}")
        if not lim.velocity > 0:
            problems.append(f"joint {j.name}: velocity limit {lim.velocity} must be > 0")
        if lim.effort < 0:
            problems.append(f"joint {j.name}: effort {lim.effort} must be >= 0")
        for name, value in (("acceleration", lim.acceleration), ("jerk", lim.jerk)):
            if value is not None and not value > 0:
                problems.append(f"joint {j.name}: {name} limit {value} must be > 0")
        norm = float(np.linalg.norm(j.axis))
        if abs(norm - 1.0) > 1e-6:
            problems.append(f"joint {j.name}: axis {j.axis} must have unit length "
                            f"(|a| = {norm:.6f})")
    first = chain.actuated_joints[0].parent if chain.actuated_joints else None
    for role in REQUIRED_FRAMES:
        frame = chain.frames.get(role)
        if frame is None or frame not in known:
            problems.append(f"REP-199 frame '{role}' is missing")
        elif role == "base" and frame == first:
            continue  # the 2012 tree: the actuator base is a body carrying joint 1
        elif role != "base_link" and chain.link(frame).elements:
            problems.append(f"REP-199 frame '{role}' ({frame}) must not carry geometry")
    for lk in chain.links:
        if lk.elements and (lk.material is None or lk.color is None):
            problems.append(f"link {lk.name}: visible geometry needs a <material>")
        for e in lk.elements:
            if isinstance(e.shape, CylinderShape) and not (e.shape.radius > 0
                                                           and e.shape.length > 0):
                problems.append(f"link {lk.name}: cylinder radius and length must be > 0")
    return problems


def find_check_urdf() -> str | None:
    """Path of the check_urdf executable (the venv's bin, the cmeel prefix, or PATH)."""
    here = Path(sys.executable).parent / "check_urdf"
    if here.exists():
        return str(here)
    for base in sys.path:
        cand = Path(base) / "cmeel.prefix" / "bin" / "check_urdf"
        if cand.exists():
            return str(cand)
    return shutil.which("check_urdf")


def structural_problems(urdf: str, expected_joints: list[str]) -> list[str]:
    """What ``check_urdf`` and yourdfpy say about the URDF text."""
    problems = []
    exe = find_check_urdf()
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "robot.urdf")
        Path(path).write_text(urdf)
        if exe is None:
            problems.append("check_urdf was not found (it ships with cmeel-urdfdom, a dependency "
                            "of pin); reinstall usar-arm")
        else:
            run = subprocess.run([exe, path], capture_output=True, text=True, timeout=60)
            if run.returncode != 0:
                detail = (run.stderr or run.stdout).strip().splitlines()
                problems.append(f"check_urdf failed (exit {run.returncode}): "
                                + " | ".join(detail[-3:]))
    try:
        from usar_arm.urdf.description_reader import actuated_joint_names

        names = actuated_joint_names(urdf)
        if names != expected_joints:
            problems.append(f"yourdfpy reads actuated joints {names}, expected {expected_joints}")
    except ValueError as exc:
        problems.append(f"yourdfpy cannot load it: {exc}")
    return problems


def validate(chain: KinematicChain, urdf: str) -> None:
    """Raise :class:`ValidationError` listing every problem with ``chain`` and its URDF."""
    problems = semantic_problems(chain) + structural_problems(urdf, list(chain.joint_names))
    if problems:
        raise ValidationError(f"robot description of {chain.name}", problems)
