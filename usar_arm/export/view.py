"""Interactive 3D replays in a web browser, with viser (the optional extra ``usar-arm[viz]``).

:func:`serve_replay` serves a live page (play/pause, loop, speed and a time slider);
:func:`export_html` writes one self-contained HTML file that replays the motion on a timeline,
viewable offline. The arm comes from its URDF text (yourdfpy), obstacles from a
:class:`~usar_arm.planning.scene.Scene`; lengths in m, times in s.

viser is imported lazily (:mod:`.viser_page`), so the rest of the package works without it.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.control.trajectory import Trajectory
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.fileio import write_atomic
from usar_arm.core.spatial import Array
from usar_arm.export.viser_page import (
    ReplayServer,
    add_ground,
    add_obstacles,
    load_urdf,
    load_viser,
    quiet,
)
from usar_arm.planning.scene import Scene

log = logging.getLogger("usar_arm.export.view")

PATH_RGB = (31, 79, 191)


@dataclass
class _Replay:
    """The arm in a viser scene, posed from trajectory time (s)."""

    robot: Any
    trajectory: Trajectory
    columns: Array

    def show(self, time_s: float) -> None:
        self.robot.update_cfg(self.trajectory.at(time_s)[0][self.columns])


def _columns(urdf: Any, trajectory: Trajectory) -> Array:
    """Trajectory column of each actuated URDF joint."""
    names = list(urdf.actuated_joint_names)
    missing = [n for n in names if n not in trajectory.joint_names]
    if missing:
        raise InvalidInputError(f"the trajectory has no values for the URDF's joints "
                                f"{', '.join(missing)} "
                                f"(it has {', '.join(trajectory.joint_names)})")
    return np.array([trajectory.joint_names.index(n) for n in names])


def _tool_path(urdf: Any, replay: _Replay, frame: str = "tool0", points: int = 200) -> Array:
    """tool0 positions (m) along the trajectory, by the URDF's forward kinematics."""
    if frame not in urdf.link_map:
        return np.zeros((0, 3))
    out = []
    for s in np.linspace(0.0, replay.trajectory.duration, points):
        urdf.update_cfg(replay.trajectory.at(s)[0][replay.columns])
        out.append(urdf.get_transform(frame, urdf.base_link)[:3, 3])
    return np.array(out)


def _build(server: Any, urdf_text: str, trajectory: Trajectory, scene: Scene | None) -> _Replay:
    """Put the arm, the obstacles, the ground grid, the tool path and a camera in the scene."""
    viser = load_viser()
    urdf = load_urdf(urdf_text)
    replay = _Replay(None, trajectory, _columns(urdf, trajectory))
    path = _tool_path(urdf, replay)
    add_ground(server)
    server.scene.add_frame("/base_link_axes", axes_length=0.25, axes_radius=0.008)
    if scene is not None:
        add_obstacles(server, scene)
    if len(path) > 1:
        server.scene.add_spline_catmull_rom("/tool0_path", path, color=PATH_RGB,
                                            thickness=0.012)
    replay.robot = viser.extras.ViserUrdf(server, urdf, root_node_name="/arm")
    replay.show(0.0)
    centre = np.vstack([path, [[0.0, 0.0, 0.8]]]).mean(axis=0) if len(path) else np.zeros(3)
    server.initial_camera.look_at = centre
    server.initial_camera.position = centre + np.array([2.2, -3.2, 1.6])
    return replay


TIME_STEP = 0.01
"""The time slider's step (s). Its box is a few digits wide: the slider's value and its end
are kept to this step, so that the box shows them whole (a time of 0.23075 s showed 0.2307)."""


def time_box(seconds: float) -> float:
    """The time slider's end for a motion of ``seconds``: rounded up to :data:`TIME_STEP`."""
    return max(TIME_STEP, round(math.ceil(round(seconds / TIME_STEP, 6)) * TIME_STEP, 2))


def serve_replay(urdf_text: str, trajectory: Trajectory, scene: Scene | None = None,
                 host: str = "127.0.0.1", port: int = 8080, loop: bool = True,
                 fps: float = 30.0) -> ReplayServer:
    """Serve an interactive page replaying ``trajectory`` in real time (returns at once).

    The page shows the arm, the scene's obstacles and the tool0 path, with a play/pause box, a
    loop box, a speed slider (x real time) and a time slider (s) to scrub. ``port`` 0 picks a
    free port (the next free one is used if ``port`` is taken); ``fps`` is the update rate (Hz).

    Returns:
        a :class:`ReplayServer` (``url``, ``stop()``, ``wait()``; also a context manager).
    """
    viser = load_viser()
    with quiet():
        server = viser.ViserServer(host=host, port=port, verbose=False)
    try:
        replay = _build(server, urdf_text, trajectory, scene)
        duration = trajectory.duration
        gui = server.gui
        gui.add_markdown(f"**{len(trajectory.joint_names)} joints**, {duration:.2f} s "
                         f"({trajectory.motion.upper()}, {trajectory.mode})")
        playing = gui.add_checkbox("Play", initial_value=True)
        looping = gui.add_checkbox("Loop", initial_value=loop)
        speed = gui.add_slider("Speed (x)", min=0.1, max=2.0, step=0.1, initial_value=1.0)
        slider = gui.add_slider("Time (s)", min=0.0, max=time_box(duration), step=TIME_STEP,
                                initial_value=0.0)
    except BaseException:
        with quiet():
            server.stop()
        raise
    slider.on_update(lambda _event: replay.show(float(slider.value)))
    handle = ReplayServer(f"http://{host}:{server.get_port()}", server)

    clock = [time.perf_counter()]  # (the wall time of the last step, s)

    def play() -> None:
        now = time.perf_counter()
        step, clock[0] = (now - clock[0]) * float(speed.value), now
        if not playing.value:
            return
        t = float(slider.value) + step
        if t > duration:
            t = 0.0 if looping.value else duration
            playing.value = bool(looping.value)
        slider.value = round(t, 2)  # (to TIME_STEP: the box shows it whole)

    handle.every(1.0 / fps, play, "usar-arm-replay")
    log.info("replay served at %s", handle.url)
    return handle


def export_html(path: str | Path, urdf_text: str, trajectory: Trajectory,
                scene: Scene | None = None, fps: float = 30.0) -> Path:
    """Write a self-contained HTML page that replays ``trajectory`` (no server needed).

    viser records the scene and one arm pose every 1/``fps`` s (Hz) of trajectory time; its
    embedded player shows a timeline. A loopback server runs on a free port while recording.

    Returns:
        ``path`` (written atomically).
    """
    if fps <= 0:
        raise InvalidInputError(f"fps must be positive, got {fps}")
    viser = load_viser()
    with quiet():
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
        try:
            replay = _build(server, urdf_text, trajectory, scene)
            recorder = server.get_scene_serializer()
            frames = max(2, int(np.ceil(trajectory.duration * fps)) + 1)
            for s in np.linspace(0.0, trajectory.duration, frames):
                replay.show(float(s))
                recorder.insert_sleep(trajectory.duration / (frames - 1))
            html = recorder.as_html()
        finally:
            server.stop()
    log.info("wrote a %d-frame replay (%.0f kB) to %s", frames, len(html) / 1e3, path)
    return write_atomic(path, html)
