"""GEO and CONF lines of both arms, character by character, against lines derived by hand from the
robot specs (usar_arm/sim/robots/*.yaml) and the protocol (docs/protocol.md sections 2 and 6),
read over raw TCP: no usar_arm parser or number formatter is involved.

How each number was derived (once, with scipy's rotations and plain float32 arithmetic, outside
usar_arm; pasted here as literals):

* CONF: per joint ``{Link i} {JointType T} {MaxTorque f} {MinValue lo} {MaxValue hi}``, the spec's
  max_force and limits with 4 decimals.
* GEO Location of link i: the spec offset minus the parent joint's offset, as UDK computes it in
  float32 Unreal units (x 250, z negated, difference, / 250, z negated back), printed by
  FloatString(p=3): integer part, then int(float32(fraction * 1000)): truncated. The KR60's link 3:
  -1.801 - (-0.796) = -1.005 exactly, in float32 -1.00499999523, so it prints -1.004.
* GEO Orientation of link i: the relative rotation R(parent direction)^T R(own direction) with
  R(r, p, y) = Rz(y) Ry(p) Rx(r) (scipy ``Rotation.from_euler("xyz", ...)``: extrinsic x, y, z),
  back to roll, pitch, yaw (``as_euler("xyz")``), rounded to 2 decimals (-0.00 prints 0.00).
  E.g. the KR60's link 2: R(3.1415, 0, 0)^T R(-1.571, 1.571, 0) -> (-1.99793, -1.57057, -2.71466)
  -> -2.00,-1.57,-2.71; the Fanuc's link 2: R(0, 1.5707, 0)^T R(3.142, 0, 0) ->
  (-3.14119, -1.5707, 0) -> -3.14,-1.57,0.00.
* Tip: the spec's tip_offset rounded to 2 decimals (KR60 0.048 -> 0.05; Fanuc 0).
* Tip sensor (an extension, a GroundTruth mounted on the last link): Location = tip_offset with
  FloatString(3); Orientation = R(last direction)^T as roll, pitch, yaw with FloatString(3):
  (2.3561945, 1.5705083, -2.3561945) -> 2.356,1.570,-2.356 (truncated: 1.570, not 1.571).
"""

from __future__ import annotations

import socket
import time

import pytest

from usar_arm.sim.server import SimServer

KR60_CONF = (
    "CONF {Type Actuator} {Name KR60Arm} "
    "{Link 1} {JointType Revolute} {MaxTorque 600.0000} {MinValue -3.1400} {MaxValue 3.1400} "
    "{Link 2} {JointType Revolute} {MaxTorque 1500.0000} {MinValue -2.3560} {MaxValue 0.6100} "
    "{Link 3} {JointType Revolute} {MaxTorque 700.0000} {MinValue -2.0940} {MaxValue 2.7570} "
    "{Link 4} {JointType Revolute} {MaxTorque 100.0000} {MinValue -3.1400} {MaxValue 3.1400} "
    "{Link 5} {JointType Revolute} {MaxTorque 60.0000} {MinValue -2.0760} {MaxValue 2.0760} "
    "{Link 6} {JointType Revolute} {MaxTorque 25.0000} {MinValue -3.1400} {MaxValue 3.1400}")
KR60_GEO = (
    "GEO {Type Actuator} {Name KR60Arm} {Location 0.000,0.000,0.000} "
    "{Orientation 0.000,0.000,0.000}{Mount KR60} "
    "{Link 1} {Parent 0} {Location 0.070,0.010,-0.413} {Orientation 3.14,0.00,0.00} "
    "{Link 2} {Parent 1} {Location 0.424,-0.210,-0.383} {Orientation -2.00,-1.57,-2.71} "
    "{Link 3} {Parent 2} {Location -0.004,0.060,-1.004} {Orientation 0.00,0.00,-1.57} "
    "{Link 4} {Parent 3} {Location 0.491,0.162,-0.169} {Orientation 2.36,1.57,2.36} "
    "{Link 5} {Parent 4} {Location 0.492,0.068,0.000} {Orientation -0.79,-1.57,-2.36} "
    "{Link 6} {Parent 5} {Location 0.152,-0.070,0.000} {Orientation -2.36,-1.57,2.36}"
    "{Tip 0.05,0.00,0.00}")
KR60_TRUTH_GEO = (
    "GEO {Type GroundTruth} {Name GroundTruth} {Location 0.000,0.000,0.000} "
    "{Orientation 0.000,0.000,0.000}{Mount KR60} {Name KR60ArmTipTruth} "
    "{Location 0.048,0.000,0.000} {Orientation 2.356,1.570,-2.356}{Mount KR60Arm}{MountLink 6}")
FANUC_CONF = (
    "CONF {Type Actuator} {Name Fanuc_M16iB20Arm} "
    "{Link 1} {JointType Prismatic} {MaxTorque 30.0000} {MinValue -1.5000} {MaxValue 1.5000} "
    "{Link 2} {JointType Revolute} {MaxTorque 100.0000} {MinValue -2.9670} {MaxValue 2.9670} "
    "{Link 3} {JointType Revolute} {MaxTorque 100.0000} {MinValue -1.5710} {MaxValue 2.7930} "
    "{Link 4} {JointType Revolute} {MaxTorque 50.0000} {MinValue -2.9670} {MaxValue 4.5380} "
    "{Link 5} {JointType Revolute} {MaxTorque 50.0000} {MinValue -3.4910} {MaxValue 3.4910} "
    "{Link 6} {JointType Revolute} {MaxTorque 25.0000} {MinValue -3.4910} {MaxValue 3.4910} "
    "{Link 7} {JointType Revolute} {MaxTorque 10.0000} {MinValue -7.8540} {MaxValue 7.8540}")
FANUC_GEO = (
    "GEO {Type Actuator} {Name Fanuc_M16iB20Arm} {Location 0.000,0.000,0.000} "
    "{Orientation 0.000,0.000,0.000}{Mount Fanuc_M16iB20} "
    "{Link 1} {Parent 0} {Location 0.000,0.000,0.000} {Orientation 0.00,1.57,0.00} "
    "{Link 2} {Parent 1} {Location 0.052,0.000,-0.384} {Orientation -3.14,-1.57,0.00} "
    "{Link 3} {Parent 2} {Location 0.152,-0.112,0.000} {Orientation -0.46,-1.57,2.03} "
    "{Link 4} {Parent 3} {Location -0.004,0.000,-0.772} {Orientation 0.00,0.00,-1.57} "
    "{Link 5} {Parent 4} {Location 0.184,0.112,-0.100} {Orientation 2.36,1.57,2.36} "
    "{Link 6} {Parent 5} {Location 0.560,0.000,0.000} {Orientation -0.79,-1.57,-2.36} "
    "{Link 7} {Parent 6} {Location 0.092,0.000,0.000} {Orientation -2.36,-1.57,2.36}"
    "{Tip 0.00,0.00,0.00}")
FANUC_TRUTH_GEO = (
    "GEO {Type GroundTruth} {Name GroundTruth} {Location 0.000,0.000,0.000} "
    "{Orientation 0.000,0.000,0.000}{Mount Fanuc_M16iB20} {Name Fanuc_M16iB20ArmTipTruth} "
    "{Location 0.000,0.000,0.000} {Orientation 2.356,1.570,-2.356}{Mount Fanuc_M16iB20Arm}"
    "{MountLink 7}")

CASES = {
    "USARBot.KR60": ("KR60Arm", KR60_CONF, KR60_GEO, KR60_TRUTH_GEO),
    "USARBot.Fanuc_M16iB20": ("Fanuc_M16iB20Arm", FANUC_CONF, FANUC_GEO, FANUC_TRUTH_GEO),
}


def _replies(port: int, robot: str, requests: list[str]) -> list[str]:
    """Spawn ``robot`` over raw TCP, send ``requests``; the CONF/GEO lines in answer, in order."""
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        stream = sock.makefile("rb")
        sock.sendall(f"INIT {{ClassName {robot}}} {{Name R}} {{Start RobotStart1}}\r\n".encode())
        deadline = time.monotonic() + 10
        while not stream.readline().startswith(b"STA ") and time.monotonic() < deadline:
            pass  # the robot exists once it reports its status
        sock.sendall("".join(f"{r}\r\n" for r in requests).encode())
        out: list[str] = []
        while len(out) < len(requests) and time.monotonic() < deadline:
            raw = stream.readline()
            if not raw:
                break
            assert raw.endswith(b"\r\n"), raw
            if raw.startswith((b"CONF ", b"GEO ")):
                out.append(raw[:-2].decode("ascii"))
    return out


@pytest.mark.parametrize("robot", list(CASES))
def test_conf_and_geo_lines_are_the_hand_derived_ones_character_by_character(
        sim: SimServer, robot: str) -> None:
    act, conf, geo, truth_geo = CASES[robot]
    got = _replies(sim.port, robot, [f"GETCONF {{Type Actuator}} {{Name {act}}}",
                                     f"GETGEO {{Type Actuator}} {{Name {act}}}",
                                     "GETGEO {Type GroundTruth}"])
    assert got == [conf, geo, truth_geo]
