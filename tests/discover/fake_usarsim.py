"""A tiny scripted USARSim server that describes an arbitrary arm (for generality and errors).

It shares no code with usar-arm (standard library only, its own line reading): it greets,
answers GETSTARTPOSES, spawns on INIT and then streams STA and ASTA at 10 Hz, answers
GETCONF/GETGEO from fixed lines, and takes ACT targets (0-based links), which its ASTA lines then
report (1-based links) as the joints' values.
"""

from __future__ import annotations

import itertools
import re
import socket
import threading
import time

from tests.usarsim.fake_server import FakeServer

_BLOCK = re.compile(r"\{(\w+)\s*([^}]*)\}")


def _read(line: str) -> tuple[str, list[tuple[str, str]]]:
    """The command word (upper case) and the ``{Key value}`` blocks of a line."""
    head = line.split("{", 1)[0].strip().upper()
    return head, [(k, v.strip()) for k, v in _BLOCK.findall(line)]


def fake_usarsim(conf: str, geo: str, *, greet: bool = True, answer: bool = True,
                 close_mid_geo: bool = False, arm: str = "A", dof: int = 2,
                 effectors: dict[str, tuple[str, str]] | None = None,
                 status: tuple[str, ...] = ()) -> FakeServer:
    """Serve NFO, GETSTARTPOSES, INIT (then 10 Hz ASTA), GETCONF/GETGEO from fixed lines and
    ACT (the targets become the streamed joint values). ``effectors``: ``{Type}`` -> the CONF
    and GEO lines of that effector type (the request's Name is not checked); ``status``: more
    lines streamed with every ASTA (EFF lines)."""
    effectors = effectors or {}

    def script(conn: socket.socket) -> None:
        if greet:
            conn.sendall(b"NFO {Gametype BotDeathMatch} {Level fake} {TimeLimit 0}\r\n")
        spawned = threading.Event()
        joints = [0.0] * dof

        def stream() -> None:
            t = 0.0
            while spawned.is_set():
                t += 0.1
                values = " ".join(f"{{Link {k + 1}}} {{Value {v:.4f}}}"
                                  for k, v in enumerate(joints))
                try:
                    conn.sendall(f"STA {{Time {t:.4f}}} {{Battery 99999}} {{Type StaticPlatform}}"
                                 f"\r\nASTA {{Time {t:.4f}}} {{Name {arm}}} {values}\r\n".encode()
                                 + b"".join(s.replace("{T}", f"{t:.4f}").encode() + b"\r\n"
                                            for s in status))
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
                head, blocks = _read(raw.decode().strip())
                keys = {k.lower(): v for k, v in blocks}
                if not answer:
                    continue
                if head == "GETSTARTPOSES":
                    conn.sendall(b"NFO {StartPoses 1} {Start1 0.00,0.00,0.00 0.00,0.00,0.00}\r\n")
                elif head == "INIT":
                    spawned.set()
                    threading.Thread(target=stream, daemon=True).start()
                elif head == "ACT":
                    for (key, value), (key2, value2) in itertools.pairwise(blocks):
                        if key == "Link" and key2 == "Value" and 0 <= int(value) < dof:
                            joints[int(value)] = float(value2)
                elif head == "GETCONF" and keys.get("type") == "Robot":
                    conn.sendall(b"CONF {Name R} {Type StaticPlatform} {SteeringType None} "
                                 b"{Mass 0} \r\n")
                elif head == "GETGEO" and keys.get("type") == "Robot":
                    conn.sendall(b"GEO {Type StaticPlatform} {Name R}\r\n")
                elif head in ("GETCONF", "GETGEO") and keys.get("type") in effectors:
                    line = effectors[keys["type"]][0 if head == "GETCONF" else 1]
                    if line:
                        conn.sendall(line.encode() + b"\r\n")
                elif head == "GETCONF":
                    conn.sendall(conf.encode() + b"\r\n")
                elif head == "GETGEO":
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
