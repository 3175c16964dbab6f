"""Regenerate the simulator part of the codec seed corpus (``fuzz/corpus/codec/sim-*``).

Starts the embedded simulator on a free loopback port (once per number style), talks to it
over a raw TCP socket the way a client does, and writes every line it receives, plus every
command line sent, as one corpus file each (the exact bytes, with the CRLF terminator).

    python fuzz/capture_corpus.py            # writes fuzz/corpus/codec/sim-*

The reference lines (``ref-*``) are UDK's own lines as docs/protocol.md quotes them, kept by hand
and not touched here.
"""

from __future__ import annotations

import hashlib
import socket
import sys
import time
from pathlib import Path

from usar_arm.sim.server import SimOptions, SimServer

OUT = Path(__file__).resolve().parent / "corpus" / "codec"

# What a client sends (each one also goes into the corpus as a line of its own).
COMMANDS = [
    b"GETSTARTPOSES\r\n",
    b"INIT {ClassName USARBot.KR60} {Name KR60} {Start RobotStart1}\r\n",
    b"GETCONF {Type Robot}\r\n",
    b"GETGEO {Type Robot}\r\n",
    b"GETCONF {Type Actuator} {Name KR60Arm}\r\n",
    b"GETGEO {Type Actuator} {Name KR60Arm}\r\n",
    b"GETCONF {Type GroundTruth}\r\n",
    b"GETGEO {Type GroundTruth}\r\n",
    b"ACT {Name KR60Arm} {Link 0} {Value 0.1000} {Link 1} {Value -0.2000} {Link 2} "
    b"{Value 0.3000} {Link 3} {Value 0.0000} {Link 4} {Value 0.5000} {Link 5} {Value 0.0000}\r\n",
]
FANUC = [
    b"INIT {ClassName USARBot.Fanuc_M16iB20} {Name Fanuc} {Location 0, 0, 0} "
    b"{Rotation 0, 0, 0}\r\n",
    b"GETCONF {Type Actuator}\r\n",
    b"GETGEO {Type Actuator}\r\n",
]


def capture(style: str, commands: list[bytes], seconds: float = 1.5) -> list[bytes]:
    """Every line the simulator sends during one session, terminator included."""
    server = SimServer(SimOptions(port=0, wire_precision=style))
    port = server.start()
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
            for cmd in commands:
                sock.sendall(cmd)
                time.sleep(0.3 if cmd.startswith(b"INIT") else 0.05)
            sock.settimeout(0.2)
            data = b""
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                try:
                    data += sock.recv(65536)
                except TimeoutError:
                    pass
    finally:
        server.stop()
    return [line + b"\r\n" for line in data.split(b"\r\n") if line]


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    seen: dict[bytes, str] = {}
    for style in ("udk", "full"):
        for session in (COMMANDS, FANUC):
            lines = capture(style, session)
            kinds: dict[bytes, int] = {}
            for line in [*session, *lines]:
                head = line.split(b" ", 1)[0].strip()
                kinds[head] = kinds.get(head, 0) + 1
                if kinds[head] > 3 or line in seen:  # a few of each stream line is enough
                    continue
                digest = hashlib.sha1(line).hexdigest()[:10]
                seen[line] = f"sim-{style}-{head.decode().lower()}-{digest}"
    for line, name in seen.items():
        (OUT / name).write_bytes(line)
    print(f"wrote {len(seen)} lines to {OUT}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
