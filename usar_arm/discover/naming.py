"""Joint and link naming schemes: ROS-Industrial, KUKA's ROS 2 stack, and the 2012 NIST package."""

from __future__ import annotations

from dataclasses import dataclass

SCHEMES = ("ros-i", "kuka-ros2", "legacy-2012")


@dataclass(frozen=True)
class Naming:
    """Names of every generated joint and link.

    ``ros-i``: joint_a1.., link_1.., base_link, base, flange, tool0 (ROS-Industrial KUKA).
    ``kuka-ros2``: joint_1.., link_1.., same frames (kroshu/kuka_robot_descriptions).
    ``legacy-2012``: <Arm>_joint_1.., <Arm>_link0..n, <Arm>_tip (hrnr/ros-usarsim), with the
    actuator base as its own link, mounted on base_link by a fixed ``<Arm>_mount`` joint.
    """

    scheme: str
    actuator: str

    def __post_init__(self) -> None:
        if self.scheme not in SCHEMES:
            raise ValueError(f"unknown naming scheme '{self.scheme}' "
                             f"(expected one of: {', '.join(SCHEMES)})")

    @property
    def legacy(self) -> bool:
        """True for the 2012 scheme (actuator base as its own link)."""
        return self.scheme == "legacy-2012"

    def joint(self, k: int) -> str:
        """Name of the k-th actuated joint (1-based)."""
        if self.scheme == "ros-i":
            return f"joint_a{k}"
        if self.scheme == "kuka-ros2":
            return f"joint_{k}"
        return f"{self.actuator}_joint_{k}"

    def link(self, k: int) -> str:
        """Name of the link moved by joint k (1-based); k = 0 is the actuator base (legacy)."""
        if self.legacy:
            return f"{self.actuator}_link{k}"
        return f"link_{k}"

    base_link = "base_link"
    tool0 = "tool0"

    @property
    def base(self) -> str:
        """The controller base frame (KUKA $ROBROOT)."""
        return f"{self.actuator}_link0" if self.legacy else "base"

    @property
    def flange(self) -> str:
        """The flange frame at the tip."""
        return f"{self.actuator}_tip" if self.legacy else "flange"

    def mount_joint(self) -> str:
        """The fixed joint base_link -> base."""
        return f"{self.actuator}_mount" if self.legacy else f"{self.base_link}-{self.base}"

    def flange_joint(self, n: int) -> str:
        """The fixed joint link_n -> flange."""
        return f"{self.actuator}_tip_joint" if self.legacy else f"{self.joint(n)}-{self.flange}"

    def tool0_joint(self) -> str:
        """The fixed joint flange -> tool0."""
        return f"{self.flange}-{self.tool0}"

    @staticmethod
    def sensor_joint(sensor: str) -> str:
        """The fixed joint carrying a mounted sensor's frame."""
        return f"{sensor}_mount"
