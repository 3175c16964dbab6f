"""Forward kinematics and Jacobians of a URDF, with Pinocchio.

This is the only module that imports ``pinocchio``. Configurations are numpy arrays in the order
of the URDF's actuated joints from the root outwards (the order of
:attr:`usar_arm.core.model.KinematicChain.joint_names`); lengths in m, angles in rad.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pinocchio as pin

from usar_arm.core.errors import ValidationError
from usar_arm.core.spatial import Array, pose_error


class KinematicModel:
    """A Pinocchio model of a URDF.

    Args:
        urdf: the URDF text.
        joint_names: expected actuated joint order; checked against the URDF.
        roles: frame role -> link (``tool0`` -> the planning tip): :meth:`frame_pose` answers
            a role with its link's pose.

    Raises:
        ValidationError: Pinocchio cannot load the URDF, or its joints differ from
            ``joint_names``.
    """

    def __init__(self, urdf: str, joint_names: Sequence[str] | None = None,
                 roles: Mapping[str, str] | None = None):
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
        self.roles: dict[str, str] = dict(roles or {})

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
        """4x4 pose of a link in the root frame, after :meth:`update` (a copy)."""
        fid = link if isinstance(link, int) else self.frame_id(link)
        return self.data.oMf[fid].homogeneous.copy()

    def frame_pose(self, q: Array, link: str) -> Array:
        """4x4 pose of ``link`` (or of the link a frame role such as ``tool0`` names) in the
        root frame at ``q``."""
        self.update(q)
        return self.placement(self.roles.get(link, link))

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

    # ------------------------------------------------------------------ IK primitives
    @staticmethod
    def target(rot: Array, pos: Array) -> object:
        """An opaque target pose for :meth:`local_error` (built once per IK query)."""
        return pin.SE3(np.ascontiguousarray(rot, dtype=float),
                       np.ascontiguousarray(pos, dtype=float))

    def local_error(self, q: Array, frame_id: int, target: object
                    ) -> tuple[Array, float, float, Array]:
        """The frame's error to a target, in the frame's own axes, and its Jacobian.

        Returns ``(e, position_error, orientation_error, J)``: ``e`` (6,) = log6 of the
        transform from the current frame to the target (linear m; angular rad), the two
        distances (m, rad), and the LOCAL Jacobian (6 x nq) for the Newton step ``J dq = e``.
        """
        pin.computeJointJacobians(self.model, self.data, q)  # also updates the placements
        jac = pin.getFrameJacobian(self.model, self.data, frame_id, pin.ReferenceFrame.LOCAL)
        delta = pin.updateFramePlacement(self.model, self.data, frame_id).actInv(target)
        e = pin.log6(delta).vector
        t = delta.translation
        w = e[3:]
        return (e, math.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]),
                math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]), jac)

    def pose_error(self, q: Array, frame_id: int, target_rot: Array, target_pos: Array
                   ) -> tuple[Array, Array]:
        """Error of a frame against a target and the Jacobian that reduces it.

        Returns ``(e, J)``: ``e`` (6,) = (target position - position, rotation vector of
        target * current^-1), both in the root frame's axes (m, rad); ``J`` (6 x nq) the
        LOCAL_WORLD_ALIGNED Jacobian, so ``J dq = e`` is the Newton step.
        """
        jac = pin.computeFrameJacobian(self.model, self.data, q, frame_id,
                                       pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        pin.updateFramePlacement(self.model, self.data, frame_id)
        target = np.eye(4)
        target[:3, :3], target[:3, 3] = target_rot, target_pos
        return pose_error(target, self.data.oMf[frame_id].homogeneous)[0], jac

    def pose_residual(self, q: Array, frame_id: int, target_rot: Array, target_pos: Array
                      ) -> tuple[float, float]:
        """Position (m) and orientation (rad) distance of a frame from a target at ``q``."""
        pin.framesForwardKinematics(self.model, self.data, q)
        m = self.data.oMf[frame_id]
        pos = float(np.linalg.norm(target_pos - m.translation))
        rot = float(np.linalg.norm(pin.log3(target_rot @ m.rotation.T)))
        return pos, rot
