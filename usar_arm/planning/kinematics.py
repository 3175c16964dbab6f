"""Forward kinematics and Jacobians of a URDF, with Pinocchio.

This is the only module that imports ``pinocchio``. Configurations are numpy arrays in the order
of the URDF's actuated joints from the root outwards (the order of
:attr:`usar_arm.model.KinematicChain.joint_names`); lengths in m, angles in rad.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from usar_arm.errors import ValidationError
from usar_arm.spatial import Array


class KinematicModel:
    """A Pinocchio model of a URDF.

    Args:
        urdf: the URDF text.
        joint_names: expected actuated joint order; checked against the URDF.

    Raises:
        ValidationError: Pinocchio cannot load the URDF, or its joints differ from
            ``joint_names``.
    """

    def __init__(self, urdf: str, joint_names: Sequence[str] | None = None):
        try:
            self.model = pin.buildModelFromXML(urdf)
        except (RuntimeError, ValueError) as exc:
            raise ValidationError("URDF (Pinocchio)", [f"Pinocchio cannot load it: {exc}"]) from exc
        self.data = self.model.createData()
        names = [self.model.names[i] for i in range(1, self.model.njoints)]
        if self.model.nq != self.model.nv or self.model.nq != len(names):
            raise ValidationError("URDF (Pinocchio)", [
                "every actuated joint must be revolute or prismatic with one coordinate "
                f"(nq={self.model.nq}, nv={self.model.nv}, joints={names})"])
        if joint_names is not None and list(joint_names) != names:
            raise ValidationError("URDF (Pinocchio)", [
                f"joint order {names} differs from the expected {list(joint_names)}"])
        self.joint_names: tuple[str, ...] = tuple(names)
        self.lower = np.array(self.model.lowerPositionLimit, dtype=float)
        self.upper = np.array(self.model.upperPositionLimit, dtype=float)
        self._frame_ids: dict[str, int] = {}
        for fid, frame in enumerate(self.model.frames):
            if frame.type == pin.FrameType.BODY and frame.name not in self._frame_ids:
                self._frame_ids[frame.name] = fid

    @property
    def nq(self) -> int:
        """Number of joint coordinates."""
        return int(self.model.nq)

    @property
    def link_names(self) -> tuple[str, ...]:
        """Every link of the URDF."""
        return tuple(self._frame_ids)

    def frame_id(self, link: str) -> int:
        """Pinocchio frame id of a link (KeyError lists the links)."""
        try:
            return self._frame_ids[link]
        except KeyError:
            raise KeyError(f"no link '{link}'; links: {', '.join(self._frame_ids)}") from None

    def update(self, q: Array) -> None:
        """Compute every frame placement at ``q`` (then read them with :meth:`placement`)."""
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))

    def placement(self, link: str | int) -> Array:
        """4x4 pose of a link in the root frame, after :meth:`update`."""
        fid = link if isinstance(link, int) else self.frame_id(link)
        return self.data.oMf[fid].homogeneous

    def frame_pose(self, q: Array, link: str) -> Array:
        """4x4 pose of ``link`` in the root frame at ``q``."""
        self.update(q)
        return self.placement(link)

    def link_poses(self, q: Array, links: Sequence[str]) -> list[Array]:
        """4x4 poses of several links at ``q``."""
        self.update(q)
        return [self.placement(name) for name in links]

    def jacobian(self, q: Array, link: str) -> Array:
        """6 x nq Jacobian of ``link``'s origin (linear; angular), in the root frame's axes."""
        fid = self.frame_id(link)
        q = np.asarray(q, dtype=float)
        return pin.computeFrameJacobian(self.model, self.data, q, fid,
                                        pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)

    def pose_and_jacobian(self, q: Array, link: str) -> tuple[Array, Array]:
        """Both the pose (4x4) and the LOCAL_WORLD_ALIGNED Jacobian (6 x nq) of ``link``."""
        fid = self.frame_id(link)
        q = np.asarray(q, dtype=float)
        jac = pin.computeFrameJacobian(self.model, self.data, q, fid,
                                       pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        pin.updateFramePlacement(self.model, self.data, fid)
        return self.data.oMf[fid].homogeneous, jac
