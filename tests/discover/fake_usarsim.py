"""A tiny scripted USARSim server that describes an arbitrary arm (for generality and errors)."""

from __future__ import annotations

import socket
import threading
import time

from tests.usarsim.fake_server import FakeServer
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import parse_line


def fake_usarsim(conf: str, geo: str, *, greet: bool = True, answer: bool = True,
                 close_mid_geo: bool = False, arm: str = "A", dof: int = 2) -> FakeServer:
    """Serve NFO, GETSTARTPOSES, INIT (then 10 Hz ASTA), GETCONF/GETGEO from fixed lines."""

    def script(conn: socket.socket) -> None:
        if greet:
            conn.sendall(b"NFO {Gametype BotDeathMatch} {Level fake} {TimeLimit 0}\r\n")
        spawned = threading.Event()

        def stream() -> None:
            t = 0.0
            while spawned.is_set():
                t += 0.1
                values = " ".join(f"{{Link {k + 1}}} {{Value 0.0000}}" for k in range(dof))
                try:
                    conn.sendall(f"STA {{Time {t:.4f}}} {{Battery 99999}} {{Type StaticPlatform}}"
                                 f"\r\nASTA {{Time {t:.4f}}} {{Name {arm}}} {values}\r\n".encode())
                except OSError:
                    return
                time.sleep(0.1)

        buf = b""
        conn.settimeout(10)
        while True:
            chunk = conn.recv(4096)
            if not chunk:
                spawned.clear()
                return
            buf += chunk
            while b"\n" in buf:
                raw, buf = buf.split(b"\n", 1)
                msg = parse_line(raw.decode().strip())
                if not answer:
                    continue
                if isinstance(msg, m.GetStartPoses):
                    conn.sendall(b"NFO {StartPoses 1} {Start1 0.00,0.00,0.00 0.00,0.00,0.00}\r\n")
                elif isinstance(msg, m.Init):
                    spawned.set()
                    threading.Thread(target=stream, daemon=True).start()
                elif isinstance(msg, m.GetConf) and msg.type == "Robot":
                    conn.sendall(b"CONF {Name R} {Type StaticPlatform} {SteeringType None} "
                                 b"{Mass 0} \r\n")
                elif isinstance(msg, m.GetGeo) and msg.type == "Robot":
                    conn.sendall(b"GEO {Type StaticPlatform} {Name R}\r\n")
                elif isinstance(msg, m.GetConf):
                    conn.sendall(conf.encode() + b"\r\n")
                elif isinstance(msg, m.GetGeo):
                    if close_mid_geo:
                        conn.sendall(geo.encode()[: len(geo) // 2])
                        spawned.clear()
                        conn.shutdown(socket.SHUT_RDWR)
                        return
                    conn.sendall(geo.encode() + b"\r\n")

    return FakeServer(script)


# A 2-joint arm (revolute + prismatic) on a mount that is offset and turned 90 deg about z.
CONF = ("CONF {Type Actuator} {Name A} {Link 1} {JointType Revolute} {MaxTorque 10.0000} "
        "{MinValue -1.5000} {MaxValue 1.5000} {Link 2} {JointType Prismatic} "
        "{MaxTorque 50.0000} {MinValue 0.0000} {MaxValue 0.4000}")
GEO = ("GEO {Type Actuator} {Name A} {Location 0.500,0.200,-0.100} {Orientation 0.000,0.000,1.570}"
       "{Mount R} {Link 1} {Parent 0} {Location 0.000,0.000,-0.300} {Orientation 3.14,0.00,0.00} "
       "{Link 2} {Parent 1} {Location 0.400,0.000,0.000} {Orientation 0.00,1.57,0.00}"
       "{Tip 0.10,0.00,0.00}")
