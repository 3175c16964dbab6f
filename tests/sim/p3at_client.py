"""A bare TCP client of the simulator for the P3AT tests: raw lines in, parsed messages kept."""

from __future__ import annotations

import socket
import time
from collections.abc import Callable

from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import parse_line


class LineClient:
    """One connection: send lines, collect every line the server sends (raw and parsed)."""

    def __init__(self, port: int):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5.0)
        self.sock.settimeout(0.05)
        self.buffer = b""
        self.lines: list[str] = []

    def send(self, line: str) -> None:
        self.sock.sendall((line + "\r\n").encode())

    def pump(self, seconds: float) -> None:
        """Read for ``seconds`` of wall time."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                chunk = self.sock.recv(1 << 16)
            except TimeoutError:
                continue
            if not chunk:
                break
            self.buffer += chunk
            *done, self.buffer = self.buffer.split(b"\r\n")
            self.lines += [d.decode() for d in done]

    def wait_for(self, test: Callable[[str], bool], timeout: float = 10.0) -> str:
        """The first line (received so far or within ``timeout`` s) that passes ``test``."""
        end = time.monotonic() + timeout
        seen = 0
        while True:
            for line in self.lines[seen:]:
                if test(line):
                    return line
            seen = len(self.lines)
            if time.monotonic() > end:
                raise TimeoutError(f"no such line within {timeout} s; last: {self.lines[-3:]}")
            self.pump(0.05)

    def latest(self, kind: type, name: str | None = None) -> m.Message:
        """The last message of a type (and name) received so far."""
        for line in reversed(self.lines):
            if not line.startswith(("SEN", "STA")):
                continue
            msg = parse_line(line)
            if isinstance(msg, kind) and (name is None or getattr(msg, "name", None) == name):
                return msg
        raise LookupError(f"no {kind.__name__} received")

    def ask(self, line: str, head: str) -> str:
        """Send a request and return the next line starting with ``head``."""
        start = len(self.lines)
        self.send(line)
        end = time.monotonic() + 5.0
        while time.monotonic() < end:
            for reply in self.lines[start:]:
                if reply.startswith(head):
                    return reply
            self.pump(0.05)
        raise TimeoutError(f"no {head} reply to {line}")

    def close(self) -> None:
        self.sock.close()


def spawn_p3at(port: int, start: str, settle_s: float = 0.0) -> LineClient:
    """A connection whose P3AT stands at a start pose, streaming (after ``settle_s`` s)."""
    client = LineClient(port)
    client.send(f"INIT {{ClassName USARBot.P3AT}} {{Name R1}} {{Start {start}}}")
    client.wait_for(lambda line: line.startswith("STA"))
    client.pump(settle_s)
    return client
