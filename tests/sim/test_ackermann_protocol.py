"""FrontAckerman in the embedded simulator speaks UDK's lines over real TCP and drives as its
DRIVE says (docs/protocol.md section 10).

The expected texts are worked out by hand from FrontAckerman.uc, AckermanSteeredVehicle.uc and
WheeledVehicle.uc: Mass 125 + 4 x 5 + 2 x 1 = 147; MaxSpeed the front wheels' MaxVelocity,
float32 0.56 -> ``0.5600``; MaxFrontSteer the steer joints' range 0.5 - (-0.5) = ``1.0000``,
MaxRearSteer the search's start 6.28 (no rear steer joint); WheelBase 0.54 + 0.416 and
WheelSeparation 0.248 + 0.204 (front-left and rear-right wheels) in float32, 0.95600003 and
0.45200002, truncated to 4 decimals. Motion is measured from the GroundTruth stream: the
bicycle model says a steer ``a`` turns the rear axle's centre on a circle of radius
``WheelBase / tan(a)``, the chassis origin (0.416 m ahead of it) on ``hypot(that, 0.416)``.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterator

import pytest

from tests.sim.p3at_client import LineClient
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.sim.world_spec import load_world
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import parse_line

SPEED_UP = 4.0
"""Simulated seconds per wall second of this module's simulator."""
RADIUS, BASE, REAR_AXLE = 0.128, 0.956, 0.416
ROBOT_CONF = ("CONF {Name FrontAckerman} {Type GroundVehicle} {SteeringType AckermanSteered} "
              "{Mass 147.0000} {MaxSpeed 0.5600} {MaxTorque 50000.0000} {MaxFrontSteer 1.0000} "
              "{MaxRearSteer 6.2800}")
ROBOT_GEO = ("GEO {Type GroundVehicle} {Name FrontAckerman} {Dimensions 0.9560,0.4520,0.0000} "
             "{COG 0.0000,0.0000,0.0000} {WheelRadius 0.1280} {WheelSeparation 0.4520} "
             "{WheelBase 0.9560}")
NUM4 = r"-?\d+\.\d{4}"
STA = re.compile(rf"^STA {{Time {NUM4}}} {{Battery 99999}} {{Type GroundVehicle}} "
                 rf"{{LightToggle False}} {{LightIntensity 100}} {{FrontSteer ({NUM4})}} "
                 rf"{{RearSteer ({NUM4})}}$")


@pytest.fixture(scope="module")
def port() -> Iterator[int]:
    server = SimServer(SimOptions(port=0, speed=SPEED_UP), world_spec=load_world("rooms"))
    yield server.start()
    server.stop()


@pytest.fixture
def car(port: int) -> Iterator[LineClient]:
    """FrontAckerman at RobotStart2 (facing +y of the world, 5 m of free floor ahead)."""
    client = LineClient(port)
    client.send("INIT {ClassName USARBot.FrontAckerman} {Name R1} {Start RobotStart2}")
    client.wait_for(lambda line: line.startswith("STA"))
    client.pump(0.3)
    yield client
    client.close()


def _truth(client: LineClient) -> tuple[float, float, float, float]:
    """Time (s), x, y (m) and yaw (rad) of the latest ground truth."""
    msg = client.latest(m.Sen, "GndTruth")
    assert isinstance(msg, m.Sen) and msg.location and msg.orientation and msg.time
    return msg.time, msg.location[0], msg.location[1], msg.orientation[2]


def _run(client: LineClient, drive: str, seconds: float) -> tuple[float, float, float]:
    """Under ``drive``, after a run-up of 1 s (simulated), over ``seconds`` s (simulated) of
    ground truth: the forward speed (m/s), the yaw rate (rad/s) and the radius of the turn
    (m: path length over the change of heading; inf when it does not turn)."""
    client.send(drive)
    client.pump(1.0 / SPEED_UP)
    t0, x0, y0, yaw0 = _truth(client)
    samples = [(x0, y0)]
    while _truth(client)[0] < t0 + seconds:
        client.pump(0.1 / SPEED_UP)
        samples.append(_truth(client)[1:3])
    t1, x1, y1, yaw1 = _truth(client)
    length = sum(math.dist(a, b) for a, b in itertools.pairwise(samples))
    turned = math.remainder(yaw1 - yaw0, 2 * math.pi)
    forward = ((x1 - x0) * math.cos(yaw0) + (y1 - y0) * math.sin(yaw0)) / (t1 - t0)
    return forward, turned / (t1 - t0), length / abs(turned) if turned else math.inf


def test_the_vehicle_describes_itself_as_udk_does(car: LineClient) -> None:
    assert car.ask("GETCONF {Type Robot}", "CONF").rstrip() == ROBOT_CONF
    assert car.ask("GETGEO {Type Robot}", "GEO") == ROBOT_GEO
    assert car.ask("GETCONF {Type INS}", "CONF") == "CONF {Type INS} {Name InsTest} " \
                                                    "{ScanInterval 0.2000}"
    assert car.ask("GETGEO {Type GroundTruth}", "GEO").startswith(
        "GEO {Type GroundTruth} {Name GndTruth} {Location 0.000,0.000,0.000}")
    conf = parse_line(ROBOT_CONF)
    assert isinstance(conf, m.PlatformConf) and conf.name == "FrontAckerman"


def test_the_status_reports_the_last_drive_angles_as_given(car: LineClient) -> None:
    line = car.wait_for(lambda ln: ln.startswith("STA"))
    match = STA.match(line)
    assert match and match.groups() == ("0.0000", "0.0000"), line
    car.send("DRIVE {Speed 0} {FrontSteer 0.7} {RearSteer -0.25}")  # 0.7: beyond the limit
    line = car.wait_for(lambda ln: "{FrontSteer 0.7000}" in ln)  # as given, not clamped
    assert STA.match(line) and "{RearSteer -0.2500}" in line, line


def test_drive_needs_speed_and_both_steers_as_in_udk(car: LineClient) -> None:
    car.send("DRIVE {Speed 0.5} {FrontSteer 0.2}")  # no RearSteer: ignored
    car.send("DRIVE {Left 0.5} {Right 0.5}")  # a skid-steered vehicle's keys: ignored
    v, w, _ = _run(car, "DRIVE {Light false}", 1.0)
    assert abs(v) < 0.003 and abs(w) < 0.003
    assert all("{FrontSteer 0.0000}" in ln for ln in car.lines if ln.startswith("STA"))


def test_speed_is_a_wheel_spin_clamped_per_wheel(car: LineClient) -> None:
    v, w, _ = _run(car, "DRIVE {Speed 0.4} {FrontSteer 0} {RearSteer 0}", 2.0)
    assert v == pytest.approx(0.4 * RADIUS, rel=0.05) and abs(w) < 0.005
    # beyond MaxSpeed the front wheels stop at 0.56 rad/s, the rear ones at 0.8: alike here,
    # they slip against each other and the vehicle goes between the two speeds
    v, _, _ = _run(car, "DRIVE {Speed 5} {FrontSteer 0} {RearSteer 0}", 2.0)
    assert 0.95 * 0.56 * RADIUS < v < 0.8 * RADIUS
    v, _, _ = _run(car, "DRIVE {Speed 0} {FrontSteer 0} {RearSteer 0}", 1.0)
    assert abs(v) < 0.003


def test_the_steer_turns_on_the_bicycle_models_circle(car: LineClient) -> None:
    """Positive FrontSteer turns right: the yaw (z down) grows; the radius is the bicycle
    model's for the chassis origin, and the steer is clamped to the joints' 0.5 rad."""
    v, w, radius = _run(car, "DRIVE {Speed 0.5} {FrontSteer 0.3} {RearSteer 0}", 8.0)
    assert w > 0 and v > 0
    assert radius == pytest.approx(math.hypot(BASE / math.tan(0.3), REAR_AXLE), rel=0.1)
    _, w, radius = _run(car, "DRIVE {Speed 0.5} {FrontSteer -0.9} {RearSteer 0}", 5.0)
    assert w < 0
    assert radius == pytest.approx(math.hypot(BASE / math.tan(0.5), REAR_AXLE), rel=0.1)
