"""The error model: small corrections of the joint frames, the tool offset and the base pose.

Parameters (names as the calibration report prints them):

* ``<joint>.origin.{x,y,z}``: added to the actuated joint's URDF origin position (m, parent
  link's axes); ``<joint>.origin.{roll,pitch,yaw}``: a small rotation about the joint frame's own
  x, y, z axes (rad), applied after the origin's rotation (R' = R exp(w)).
* ``tool.{x,...,yaw}``: the same for the fixed joint that carries the measured frame (its
  offset from its parent link).
* ``base.{x,...,yaw}``: M_from_base_link = base_guess * [exp(w) | v] (base_link axes).

The model's pose of the measured frame in M at q is
``base * prod_j (origin_j' * motion_j(q_j))`` along the path from the root, computed here for
many configurations at once (numpy, (N, 4, 4) stacks).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from usar_arm.core.errors import CalibrationError
from usar_arm.core.model import Joint, JointType
from usar_arm.core.spatial import Array, exp_so3, matrix_to_rpy, transform
from usar_arm.urdf.description_reader import parse_urdf
from usar_arm.urdf.writer import nums

AXES = ("x", "y", "z", "roll", "pitch", "yaw")


def correction(d: Array) -> Array:
    """The 4x4 transform [exp(w) | v] of a correction d = (v, w) (m, rad)."""
    return transform(exp_so3(d[3:]), d[:3])


def _motions(joint: Joint, q: Array) -> Array:
    """(N, 4, 4) joint motions at the values q (N,)."""
    n = len(q)
    out = np.tile(np.eye(4), (n, 1, 1))
    axis = np.asarray(joint.axis, float)
    if joint.type is JointType.PRISMATIC:
        out[:, :3, 3] = q[:, None] * axis
        return out
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    s, c = np.sin(q)[:, None, None], np.cos(q)[:, None, None]
    out[:, :3, :3] = np.eye(3) + s * k + (1 - c) * (k @ k)
    return out


@dataclass(frozen=True)
class ErrorModel:
    """The path of joints from the root to the measured frame and the parameter layout."""

    path: tuple[Joint, ...]
    joint_names: tuple[str, ...]
    measured_frame: str
    tool_joint: str | None          # the fixed joint carrying the measured frame (None: no tool)
    base: bool
    names: tuple[str, ...]

    @classmethod
    def from_urdf(cls, urdf: str, measured_frame: str, base: bool = True,
                  tool: bool = True) -> ErrorModel:
        """The error model of ``urdf`` for measurements of ``measured_frame``."""
        chain, _ = parse_urdf(urdf)
        if measured_frame not in {lk.name for lk in chain.links}:
            raise CalibrationError(f"the URDF has no link '{measured_frame}' (links: "
                                   f"{', '.join(lk.name for lk in chain.links)})")
        path = tuple(chain.path_to(measured_frame))
        actuated = [j.name for j in path if j.actuated]
        if actuated != list(chain.joint_names):
            raise CalibrationError(f"the measured frame '{measured_frame}' does not follow "
                                   f"every actuated joint (its path has {actuated})")
        last = path[-1] if path else None
        tool_joint = last.name if (tool and last is not None and not last.actuated) else None
        names = [f"{j.name}.origin.{a}" for j in path if j.actuated for a in AXES]
        names += [f"tool.{a}" for a in AXES] if tool_joint else []
        names += [f"base.{a}" for a in AXES] if base else []
        return cls(path, tuple(chain.joint_names), measured_frame, tool_joint, base,
                   tuple(names))

    @property
    def size(self) -> int:
        """Number of parameters."""
        return len(self.names)

    def split(self, p: Array) -> tuple[dict[str, Array], Array | None, Array | None]:
        """Per-joint corrections, the tool's and the base's (each (6,))."""
        out, k = {}, 0
        for j in self.path:
            if j.actuated:
                out[j.name] = p[k:k + 6]
                k += 6
        tool = None
        if self.tool_joint:
            tool, k = p[k:k + 6], k + 6
        base = p[k:k + 6] if self.base else None
        return out, tool, base

    def base_pose(self, p: Array, base_guess: Array) -> Array:
        """M_from_base_link (4x4) at parameters p."""
        _, _, b = self.split(p)
        return base_guess @ correction(b) if b is not None else np.array(base_guess, float)

    def poses(self, p: Array, q: Array, base_guess: Array) -> Array:
        """(N, 4, 4) poses of the measured frame in M at joint values q (N, n)."""
        q = np.atleast_2d(np.asarray(q, float))
        joints, tool, _ = self.split(p)
        t = np.tile(self.base_pose(p, base_guess), (len(q), 1, 1))
        col = {name: i for i, name in enumerate(self.joint_names)}
        for j in self.path:
            origin = j.origin.matrix()
            if j.actuated:
                origin = corrected(origin, joints[j.name])
                t = t @ origin @ _motions(j, q[:, col[j.name]])
            else:
                if j.name == self.tool_joint and tool is not None:
                    origin = corrected(origin, tool)
                t = t @ origin
        return t

    def apply(self, urdf: str, p: Array, tip_joint: str | None = None) -> str:
        """The URDF text with the joint origins and the tool joint corrected (only those
        ``<origin>`` elements change; numbers printed as the writer prints them).

        ``tip_joint``: a fixed joint with the same parent link as the measured frame's whose
        child sits where the measured frame is (a sensor mounted at the Tip): its origin
        position becomes the calibrated measured frame's (its rotation is kept).
        """
        joints, tool, _ = self.split(p)
        for j in self.path:
            if j.actuated:
                urdf = replace_origin(urdf, j, corrected(j.origin.matrix(), joints[j.name]))
            elif j.name == self.tool_joint and tool is not None:
                mount = corrected(j.origin.matrix(), tool)
                urdf = replace_origin(urdf, j, mount)
                if tip_joint is not None:
                    urdf = self._move_tip(urdf, tip_joint, j, mount[:3, 3])
        return urdf

    @staticmethod
    def _move_tip(urdf: str, tip_joint: str, mount: Joint, position: Array) -> str:
        chain, _ = parse_urdf(urdf)
        try:
            tip = chain.joint(tip_joint)
        except KeyError:
            raise CalibrationError(f"no joint '{tip_joint}' in the URDF") from None
        if tip.parent != mount.parent or tip.actuated:
            raise CalibrationError(f"the tip joint '{tip_joint}' must be fixed and hang from "
                                   f"'{mount.parent}' as the measured frame does")
        pose = tip.origin.matrix()
        pose[:3, 3] = position
        return replace_origin(urdf, tip, pose)


def corrected(origin: Array, d: Array) -> Array:
    """origin' = [R exp(w) | t + v] for an origin [R | t] and a correction d = (v, w)."""
    out = np.array(origin, float)
    out[:3, :3] = out[:3, :3] @ exp_so3(d[3:])
    out[:3, 3] += d[:3]
    return out


def replace_origin(urdf: str, joint: Joint, pose: Array) -> str:
    xyz, rpy = pose[:3, 3], matrix_to_rpy(pose[:3, :3])
    new = f'<origin xyz="{nums(xyz)}" rpy="{nums(rpy)}"/>'
    pattern = re.compile(r'(<joint\s+name="' + re.escape(joint.name) + r'"[^>]*>)(.*?)(</joint>)',
                         re.S)
    match = pattern.search(urdf)
    if match is None:
        raise CalibrationError(f"joint '{joint.name}' not found in the URDF text")
    body = match.group(2)
    if re.search(r"<origin\b[^>]*/>", body):
        body = re.sub(r"<origin\b[^>]*/>", new, body, count=1)
    else:
        body = "\n    " + new + body
    return urdf[:match.start(2)] + body + urdf[match.end(2):]
