"""A recorded USARSim session and its replay, over real TCP: the same simulator lines for two
nodes.

:class:`Recorder` relays a client to a server (``usar-arm sim``) and keeps every line either
way with its time. :class:`Replayer` is a server that plays a recording back to one client: it
waits for each request the recorded client sent (GETSTARTPOSES, INIT, GETCONF, GETGEO...;
lines that only stream, ACT and DRIVE, are read and dropped), and sends each recorded server
line at its recorded delay after the last request, so that a node that asks the same questions
gets the same answers and the same status stream, at the same pace."""

from __future__ import annotations

import socket
import threading
import time
from dataclasses import dataclass, field

STREAMED = ("ACT", "DRIVE", "SET")
"""Client lines a replay does not wait for (their number and timing vary run to run)."""


@dataclass(frozen=True)
class Event:
    """One line: ``server`` (True: server -> client), its monotonic time (s), its text."""

    server: bool
    time: float
    line: str


@dataclass
class Recording:
    """The lines of one session, in order."""

    events: list[Event] = field(default_factory=list)


def _lines(sock: socket.socket, on_line: object, stop: threading.Event) -> None:
    buffer = b""
    sock.settimeout(0.2)
    while not stop.is_set():
        try:
            data = sock.recv(65536)
        except TimeoutError:
            continue
        except OSError:
            return
        if not data:
            return
        buffer += data
        while b"\n" in buffer:
            line, buffer = buffer.split(b"\n", 1)
            text = line.decode(errors="replace").strip("\r")
            if text:
                on_line(text)  # type: ignore[operator]


class Recorder:
    """Relays one client on a port of its own to ``(host, port)``, recording the lines."""

    def __init__(self, host: str, port: int):
        self.target = (host, port)
        self.recording = Recording()
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _record(self, server: bool, line: str) -> None:
        with self.lock:
            self.recording.events.append(Event(server, time.monotonic(), line))

    def _serve(self) -> None:
        self.listener.settimeout(0.5)
        while not self.stop.is_set():
            try:
                client, _ = self.listener.accept()
            except TimeoutError:
                continue
            server = socket.create_connection(self.target)
            for src, dst, is_server in ((client, server, False), (server, client, True)):
                def forward(line: str, dst: socket.socket = dst, is_server: bool = is_server
                            ) -> None:
                    self._record(is_server, line)
                    try:
                        dst.sendall(line.encode() + b"\r\n")
                    except OSError:
                        pass
                threading.Thread(target=_lines, args=(src, forward, self.stop),
                                 daemon=True).start()
            return  # one client

    def close(self) -> Recording:
        self.stop.set()
        self.listener.close()
        return self.recording


class Replayer:
    """Plays ``recording`` to the first client that connects (on :attr:`port`)."""

    def __init__(self, recording: Recording):
        self.recording = recording
        self.stop = threading.Event()
        self.requests: list[str] = []
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.mismatches: list[tuple[str, str]] = []
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        self.listener.settimeout(60)
        try:
            sock, _ = self.listener.accept()
        except OSError:
            return
        arrived = threading.Condition()
        got: list[str] = []

        def on_line(line: str) -> None:
            if line.split(" ", 1)[0].upper() in STREAMED:
                return
            with arrived:
                got.append(line)
                arrived.notify_all()

        threading.Thread(target=_lines, args=(sock, on_line, self.stop), daemon=True).start()
        anchor_wall, anchor_rec = time.monotonic(), self.recording.events[0].time
        taken = 0
        for event in self.recording.events:
            if self.stop.is_set():
                break
            if not event.server:
                if event.line.split(" ", 1)[0].upper() in STREAMED:
                    continue
                with arrived:
                    if not arrived.wait_for(lambda n=taken: len(got) > n or self.stop.is_set(),
                                            timeout=120):
                        return
                if self.stop.is_set():
                    break
                if got[taken] != event.line:
                    self.mismatches.append((event.line, got[taken]))
                taken += 1
                anchor_wall, anchor_rec = time.monotonic(), event.time
                continue
            delay = anchor_wall + (event.time - anchor_rec) - time.monotonic()
            if delay > 0 and self.stop.wait(delay):
                break
            try:
                sock.sendall(event.line.encode() + b"\r\n")
            except OSError:
                return
        self.stop.wait()  # the recording is over: the connection stays open, silent
        sock.close()

    def close(self) -> None:
        self.stop.set()
        self.listener.close()
