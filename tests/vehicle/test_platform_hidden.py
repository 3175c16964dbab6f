"""A vehicle over real TCP whose INS answers GETCONF but not GETGEO (hidden) and which carries
a sensor of a type usar-arm does not know: both are reported, neither is guessed."""

from __future__ import annotations

import socket
import time

from tests.usarsim.fake_server import FakeServer, read_line
from tests.vehicle.test_platform_discovery import CONF, GEO
from usar_arm.description.platform import is_ground_vehicle
from usar_arm.discover.platform import learn_platform
from usar_arm.urdf.platform import platform_urdf, validate_platform
from usar_arm.usarsim.client import UsarClient

REPLIES = {
    "GETCONF {Type Robot}": CONF,
    "GETGEO {Type Robot}": GEO,
    "GETCONF {Type GroundTruth} {Name GndTruth}": "CONF {Type GroundTruth} {Name GndTruth} "
                                                  "{ScanInterval 0.1000}",
    "GETGEO {Type GroundTruth} {Name GndTruth}": "GEO {Type GroundTruth} {Name GndTruth} "
                                                "{Location 0.000,0.000,0.000} "
                                                "{Orientation 0.000,0.000,0.000}{Mount P3AT}",
    "GETCONF {Type INS} {Name Secret}": "CONF {Type INS} {Name Secret} {ScanInterval 0.2000}",
}
"""What the server answers; GETGEO of the INS gets nothing, as UDK for a hidden item."""


def _script(conn: socket.socket) -> None:
    conn.sendall(b"NFO {Gametype BotDeathMatch} {Level fake} {TimeLimit 0}\r\n")
    read_line(conn)  # GETSTARTPOSES
    conn.sendall(b"NFO {StartPoses 1} {Start1 0.00,0.00,0.00 0.00,0.00,0.00}\r\n")
    read_line(conn)  # INIT
    conn.sendall(b"STA {Time 0.1} {Battery 99999} {Type GroundVehicle}\r\n"
                 b"SEN {Time 0.1} {Type GroundTruth} {Name GndTruth} {Location 0,0,0} "
                 b"{Orientation 0,0,0}\r\n"
                 b"SEN {Type INS} {Name Secret} {Location 0,0,0} {Orientation 0,0,0}\r\n"
                 b"SEN {Time 0.1} {Type Sonar} {Name S1} {Range 1.5}\r\n")
    while True:
        line = read_line(conn, timeout=10.0)
        if not line:
            return
        reply = REPLIES.get(line)
        if reply is not None:
            conn.sendall(reply.encode() + b"\r\n")


def test_hidden_and_unknown_sensors_are_reported_not_guessed() -> None:
    with FakeServer(_script) as srv, UsarClient("127.0.0.1", srv.port, timeout=3.0) as client:
        begin = time.monotonic()
        record, desc = learn_platform(client, "P3AT", timeout=3.0)
        seconds = time.monotonic() - begin
    assert [s.name for s in desc.sensors] == ["GndTruth"]
    assert desc.hidden == ("INS Secret",) and desc.unknown == ("Sonar S1",)
    assert seconds < 3.0  # a hidden sensor costs its own short wait, not the reply timeout
    assert not any("Sonar" in e.request for e in record.exchanges)  # never asked about
    urdf = platform_urdf(desc)
    validate_platform(desc, urdf)
    assert "INS Secret" in urdf and '"secret_link"' not in urdf


def test_a_remote_class_the_simulator_does_not_know_is_judged_by_its_status_line() -> None:
    with FakeServer(_script) as srv:
        assert is_ground_vehicle("USARBot.Kenaf", "127.0.0.1", srv.port, timeout=3.0)


def test_known_classes_decide_without_a_connection() -> None:
    # port 9 (discard) has nobody listening: a connection attempt would raise
    assert is_ground_vehicle("P3AT", "127.0.0.1", 9)
    assert not is_ground_vehicle("KR60", "127.0.0.1", 9)
