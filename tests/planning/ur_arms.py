"""Arms with three parallel axes for the tests: the UR5 of example-robot-data as shipped, and
synthetic ones written as URDFs (UR-like joint origins, other lengths, a tilted mount, flipped
axes) so the closed form is judged on more than the one arm it was written for. Metres, radians."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from usar_arm.planning.robot import Robot, RobotOptions, robot_from_files, robot_from_texts

ROOT = Path(__file__).resolve().parents[2]
UR5 = ROOT / "examples" / "robots" / "example-robot-data" / "robots" / "ur_description"


@dataclass(frozen=True)
class UrLengths:
    """A UR-type arm's offsets (m) as its URDF places them: shoulder height d1, shoulder and
    elbow side offsets, upper arm a2, forearm a3, wrist offsets d4, d5, d6; the mount's pose
    in base_link (xyz m, rpy rad), the signs of the elbow's and wrist 1's axes and the tool's
    rpy (rad) on the last link."""

    d1: float
    shoulder: float
    elbow: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float
    mount_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mount_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    elbow_sign: int = 1
    wrist_sign: int = 1
    tool_rpy: tuple[float, float, float] = (-1.5707963267948966, 0.0, 0.0)
    miss: float = 0.0
    """m: axis 6 moved this far off axis 5 (a real arm's deviation from the class)."""
    tilt: float = 0.0
    """rad: the elbow's axis tilted this much out of parallel (likewise)."""


UR10 = UrLengths(0.1273, 0.220941, 0.1719, 0.612, 0.5723, 0.1149, 0.1157, 0.0922)
ODD = UrLengths(0.3, 0.05, 0.2, 0.45, 0.3, 0.07, 0.12, 0.15, (0.1, -0.2, 0.4), (0.3, -0.2, 0.5),
                -1, -1, (0.4, -1.1, 0.7))
"""Other lengths, a tilted mount, the elbow's and wrist 1's axes reversed, a skewed tool."""
NEAR = UrLengths(0.1625, 0.138, 0.131, 0.425, 0.3922, 0.127, 0.0997, 0.0996, miss=0.001,
                 tilt=0.004)
"""UR5e-like lengths, axes 5 and 6 a millimetre apart and the elbow 4 mrad out of parallel:
in the class within its tolerance, not exactly."""

_TURN = "-6.283185307179586", "6.283185307179586"
_HALF = "-3.141592653589793", "3.141592653589793"


def _joint(name: str, parent: str, child: str, xyz: tuple[float, ...], rpy: tuple[float, ...],
           axis: str | None, limits: tuple[str, str] = _TURN) -> str:
    kind = "fixed" if axis is None else "revolute"
    text = (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{" ".join(map(str, xyz))}" '
            f'rpy="{" ".join(map(str, rpy))}"/>')
    if axis is not None:
        text += (f'<axis xyz="{axis}"/><limit lower="{limits[0]}" upper="{limits[1]}" '
                 'effort="100" velocity="3"/>')
    return text + "</joint>"


def ur_urdf(name: str, g: UrLengths) -> str:
    """The URDF of a UR-type arm with lengths ``g`` (joint origins as the UR5's URDF)."""
    half = 1.5707963267948966
    links = ["base_link", "mount", "shoulder_link", "upper_arm_link", "forearm_link",
             "wrist_1_link", "wrist_2_link", "wrist_3_link", "tool0"]
    joints = [
        _joint("mount_joint", "base_link", "mount", g.mount_xyz, g.mount_rpy, None),
        _joint("shoulder_pan_joint", "mount", "shoulder_link", (0, 0, g.d1), (0, 0, 0), "0 0 1"),
        _joint("shoulder_lift_joint", "shoulder_link", "upper_arm_link", (0, g.shoulder, 0),
               (0, half, 0), "0 1 0"),
        _joint("elbow_joint", "upper_arm_link", "forearm_link", (0, -g.elbow, g.a2),
               (g.tilt, 0, 0), f"0 {g.elbow_sign} 0", _HALF),
        _joint("wrist_1_joint", "forearm_link", "wrist_1_link", (0, 0, g.a3), (0, half, 0),
               f"0 {g.wrist_sign} 0"),
        _joint("wrist_2_joint", "wrist_1_link", "wrist_2_link", (0, g.d4, 0), (0, 0, 0),
               "0 0 1"),
        _joint("wrist_3_joint", "wrist_2_link", "wrist_3_link", (g.miss, 0, g.d5), (0, 0, 0),
               "0 1 0"),
        _joint("tool0_joint", "wrist_3_link", "tool0", (0, g.d6, 0), g.tool_rpy, None)]
    return (f'<robot name="{name}">' + "".join(f'<link name="{lk}"/>' for lk in links)
            + "".join(joints) + "</robot>")


def synthetic(name: str, g: UrLengths) -> Robot:
    """A Robot of the UR-type arm ``g``."""
    return robot_from_texts({f"{name}.urdf": ur_urdf(name, g)})


def ur5() -> Robot:
    """The UR5 of example-robot-data, solved for ``ee_link`` as examples/09_any_urdf.py does."""
    return robot_from_files(UR5 / "urdf" / "ur5_robot.urdf", UR5 / "srdf" / "ur5.srdf",
                            options=RobotOptions.of(tip="ee_link"))
