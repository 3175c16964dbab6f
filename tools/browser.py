"""Headless Chromium, driven over the DevTools protocol, for the tests that open usar-arm's web
pages as a user would (``usar-arm view``'s viser page, the documentation site) and for the
viewer's screenshot in the docs (``tools/pictures.py``).

:func:`chromium` finds the browser, installing Debian's ``chromium`` package where the package
manager can (the tests run as root on Debian, as CI does); :class:`Page` loads a URL, collects
every console error and uncaught exception, evaluates JavaScript and takes screenshots. The
flags keep Chromium off the network (this machine has none but loopback) and render WebGL in
software (SwiftShader).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
INSTALL = "apt-get install -y --no-install-recommends chromium fonts-dejavu-core"
"""The command that installs what the browser tests need (Debian 12, as root)."""
FLAGS = ("--headless=new", "--no-sandbox", "--use-gl=swiftshader", "--enable-unsafe-swiftshader",
         "--disable-gpu-sandbox", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--disable-quic",
         "--disable-default-apps", "--disable-extensions", "--mute-audio",
         "--window-size=1280,800", "--hide-scrollbars")


class BrowserUnavailable(RuntimeError):
    """No Chromium, and no package manager that could install it (the message says how)."""


def chromium() -> str:
    """The Chromium executable; installed with apt-get first when missing and apt-get exists.

    Raises:
        BrowserUnavailable: no Chromium and no apt-get (the message gives the install command).
        RuntimeError: apt-get could not install it (with its output).
    """
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found:
        return found
    if shutil.which("apt-get") is None or os.geteuid() != 0:
        raise BrowserUnavailable(f"no Chromium; install it with: {INSTALL}")
    for command in ("apt-get update -qq", INSTALL):
        done = subprocess.run(command.split(), capture_output=True, text=True, check=False,
                              timeout=900, env={**os.environ, "DEBIAN_FRONTEND": "noninteractive"})
        if done.returncode != 0:
            raise RuntimeError(f"{command} failed:\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    found = shutil.which("chromium")
    if not found:
        raise RuntimeError(f"{INSTALL} installed no chromium executable")
    return found


@dataclass
class Page:
    """One tab of a headless Chromium of its own, driven over the DevTools protocol.

    Attributes:
        errors: every console error, uncaught exception and failed load the page reported.
    """

    process: subprocess.Popen[bytes]
    socket: Any
    profile: tempfile.TemporaryDirectory[str]
    errors: list[str] = field(default_factory=list)
    events: list[dict[str, Any]] = field(default_factory=list)
    _next: int = 0

    @classmethod
    def open(cls, width: int = 1280, height: int = 800) -> Page:
        """Start Chromium on a blank tab of ``width`` x ``height`` pixels."""
        from websockets.sync.client import connect

        profile = tempfile.TemporaryDirectory(prefix="usar-arm-chromium-")
        process = subprocess.Popen(
            [chromium(), *FLAGS, f"--window-size={width},{height}",
             f"--user-data-dir={profile.name}", "--remote-debugging-port=0", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
        port_file = Path(profile.name) / "DevToolsActivePort"
        deadline = time.monotonic() + 60
        while not port_file.is_file() or len(port_file.read_text().split()) < 2:
            if process.poll() is not None or time.monotonic() > deadline:
                process.kill()
                said = process.stderr.read() if process.stderr else b""
                raise RuntimeError(f"Chromium did not start: {said[-2000:]!r}")
            time.sleep(0.05)
        port = int(port_file.read_text().split()[0])
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as reply:
            tab = next(t for t in json.load(reply) if t["type"] == "page")
        page = cls(process, connect(tab["webSocketDebuggerUrl"], max_size=2**28,
                                    open_timeout=30), profile)
        for method in ("Page.enable", "Runtime.enable", "Log.enable"):
            page.call(method)
        page.call("Emulation.setDeviceMetricsOverride", width=width, height=height,
                  deviceScaleFactor=1, mobile=False)
        return page

    def call(self, method: str, timeout: float = 60.0, **params: Any) -> dict[str, Any]:
        """Send one DevTools command and return its result, keeping the events meanwhile.

        Raises:
            RuntimeError: the browser answered with an error. TimeoutError: no answer in time.
        """
        self._next += 1
        ident = self._next
        self.socket.send(json.dumps({"id": ident, "method": method, "params": params}))
        deadline = time.monotonic() + timeout
        while True:
            message = json.loads(self.socket.recv(timeout=max(0.01, deadline - time.monotonic())))
            if message.get("id") == ident:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return dict(message.get("result", {}))
            self._event(message)

    def _event(self, message: dict[str, Any]) -> None:
        method, params = message.get("method", ""), message.get("params", {})
        self.events.append(message)
        if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            self.errors.append("console: " + " ".join(
                str(a.get("value", a.get("description", ""))) for a in params.get("args", [])))
        elif method == "Runtime.exceptionThrown":
            details = params.get("exceptionDetails", {})
            self.errors.append("exception: " + str(details.get("exception", {}).get(
                "description", details.get("text", ""))))
        elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
            entry = params["entry"]
            self.errors.append(f"log: {entry.get('text', '')} {entry.get('url', '')}".strip())

    def pump(self, seconds: float) -> None:
        """Keep reading the page's events for ``seconds`` (the page runs meanwhile)."""
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            try:
                self._event(json.loads(self.socket.recv(timeout=left)))
            except TimeoutError:
                return

    def goto(self, url: str, timeout: float = 60.0) -> None:
        """Load ``url`` and wait for its load event.

        Raises:
            RuntimeError: the page failed to load (the browser's reason).
        """
        self.events.clear()
        result = self.call("Page.navigate", url=url)
        if result.get("errorText"):
            raise RuntimeError(f"{url}: {result['errorText']}")
        deadline = time.monotonic() + timeout
        while not any(e.get("method") == "Page.loadEventFired" for e in self.events):
            if time.monotonic() > deadline:
                raise TimeoutError(f"{url} did not load within {timeout:g} s")
            self.pump(0.1)

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression in the page (awaited when it is a promise).

        Raises:
            RuntimeError: the expression threw (with the page's description).
        """
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True,
                           awaitPromise=True)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result.get("result", {}).get("value")

    def wait_for(self, expression: str, timeout: float = 60.0) -> Any:
        """Evaluate ``expression`` until it is truthy (the page running meanwhile); its value.

        Raises:
            TimeoutError: it stayed falsy for ``timeout`` s.
        """
        deadline = time.monotonic() + timeout
        while not (value := self.evaluate(expression)):
            if time.monotonic() > deadline:
                raise TimeoutError(f"not true within {timeout:g} s: {expression}")
            self.pump(0.2)
        return value

    def screenshot(self, path: Path | None = None) -> bytes:
        """A PNG of the viewport (written to ``path`` too, when given)."""
        import base64

        data = base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"])
        if path is not None:
            path.write_bytes(data)
        return data

    def close(self) -> None:
        """End the browser (and its profile folder)."""
        try:
            self.socket.close()
        finally:
            # Chromium's helpers (renderer, GPU, crash handler) outlive the browser process a
            # moment and write into the profile: end the whole session, then remove the folder
            # ("Directory not empty: 'Default'" was a removal racing a helper's last write).
            try:
                os.killpg(self.process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.process.wait(timeout=30)
            for _ in range(50):
                shutil.rmtree(self.profile.name, ignore_errors=True)
                if not Path(self.profile.name).exists():
                    break
                time.sleep(0.1)
            self.profile.cleanup()

    def __enter__(self) -> Page:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def pixels(png: bytes) -> Any:
    """The (height, width, 3) uint8 RGB array of a PNG."""
    import io

    import numpy as np
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


BENIGN = re.compile(r"favicon\.ico")
"""Console errors that say nothing about the page (a browser asks for /favicon.ico itself)."""


def page_errors(page: Page) -> list[str]:
    """The page's errors, less :data:`BENIGN` ones."""
    return [e for e in page.errors if not BENIGN.search(e)]


# ------------------------------------------------------------------ the viewer's screenshot

VIEW_INPUTS = ("robots/generated/KR60.urdf", "robots/generated/KR60.srdf",
               "robots/generated/KR60.joint_limits.yaml", "usar_arm/data/scenes/table.yaml",
               "usar_arm/export/view.py", "usar_arm/export/viser_page.py",
               "usar_arm/cli/picture_cmds.py", "usar_arm/cli/plan_cmd.py", "tools/browser.py")
PLAN = ("plan", "--urdf", "{root}/robots/generated/KR60.urdf", "--scene", "table", "--pose",
        "1.45", "-0.45", "1.1", "0", "3.14159", "0", "--out", "traj.json")


def serve_view(trajectory: Path, cwd: Path, *extra: str) -> tuple[subprocess.Popen[str], str]:
    """Start ``usar-arm view TRAJECTORY`` on a free port; the process and the page's URL."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    process = subprocess.Popen([sys.executable, "-m", "usar_arm", "view", str(trajectory),
                                "--http-port", str(port), *extra], cwd=cwd, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               env={**os.environ, "PYTHONPATH": str(ROOT)})
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 120
    while True:
        try:
            with urllib.request.urlopen(url, timeout=2):
                return process, url
        except OSError:
            if process.poll() is not None or time.monotonic() > deadline:
                process.kill()
                raise RuntimeError(f"usar-arm view did not serve {url}: "
                                   f"{(process.stdout.read() if process.stdout else '')[-2000:]}"
                                   ) from None
            time.sleep(0.2)


VIEWER_READY = ("(() => { const c = Array.from(document.querySelectorAll('canvas'))"
                ".find(c => c.width > 0); return c !== undefined && getComputedStyle(c).opacity"
                " === '1' && document.body.innerText.includes('Time'); })()")
"""True once viser's page shows its 3D canvas and the replay's controls."""


DISMISS = ("Array.from(document.querySelectorAll('button')).filter(b => b.parentElement && "
           "b.parentElement.innerText.includes('Software WebGL')).forEach(b => b.click())")
"""Closes viser's notice that WebGL runs in software (headless Chromium has no GPU)."""


def _viewer(out: Path, scratch: Path) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from pictures import usar_arm

    usar_arm(*(a.replace("{root}", str(ROOT)) for a in PLAN), cwd=scratch)
    process, url = serve_view(scratch / "traj.json", scratch)
    try:
        with Page.open(1280, 800) as page:
            page.goto(url)
            page.wait_for(VIEWER_READY)
            page.pump(4.0)  # the scene streams in over the page's websocket
            page.evaluate(DISMISS)  # (a user with a GPU never sees it)
            page.pump(1.0)
            page.screenshot(out)
    finally:
        process.kill()
        process.wait(timeout=30)


def _register() -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from pictures import PICTURES, Picture, register

    if "viewer" not in PICTURES:
        register(Picture("docs/images/viewer.png",
                         "usar-arm " + " ".join(PLAN) + "; usar-arm view traj.json, in headless "
                         "Chromium at 1280x800 (tools/browser.py)", VIEW_INPUTS, _viewer))


_register()
