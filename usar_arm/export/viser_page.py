"""The parts of a viser page that every 3D view of usar-arm shares (:mod:`.view`, the replay
of a trajectory; :mod:`.reach_view`, a reachability map): viser itself (the optional extra
``usar-arm[viz]``, imported when a view is asked for), the arm from its URDF text, the ground
and a scene's obstacles, and a running page. Lengths in m.

viser prints a banner when a server starts and a line when it stops, whatever its ``verbose``
flag; :func:`quiet` silences both (the library never prints).
"""

from __future__ import annotations

import contextlib
import io
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from usar_arm.core.errors import InvalidInputError
from usar_arm.core.spatial import quat_from_matrix
from usar_arm.planning.scene import Box, CylinderShape, Scene, Sphere

OBSTACLE_RGB = (150, 160, 175)
OBSTACLE_OPACITY = 0.4


def load_viser() -> Any:
    """The viser module (with ``viser.extras``).

    Raises:
        InvalidInputError: viser is not installed (the message says how to install it).
    """
    try:
        import viser
        import viser.extras
    except ImportError as exc:
        raise InvalidInputError(f"the 3D viewer needs viser ({exc.msg}); install with "
                                "pip install 'usar-arm[viz]'") from None
    return viser


def load_urdf(urdf_text: str) -> Any:
    """The arm of ``urdf_text`` as the viewer draws it (yourdfpy, meshes resolved).

    Raises:
        InvalidInputError: the URDF cannot be read (with the reader's reason).
    """
    from usar_arm.urdf.description_reader import viewer_urdf

    try:
        return viewer_urdf(urdf_text)
    except ValueError as exc:
        raise InvalidInputError(f"cannot read the URDF for the viewer: {exc}") from None


def add_obstacles(server: Any, scene: Scene) -> None:
    """Draw each of ``scene``'s objects in ``server``'s scene, translucent, under ``/scene/``."""
    from usar_arm.urdf.meshes import cylinder_mesh

    for obj in scene.objects:
        name, s = f"/scene/{obj.name}", obj.shape
        pose = {"wxyz": quat_from_matrix(obj.pose[:3, :3]), "position": obj.pose[:3, 3]}
        look = {"color": OBSTACLE_RGB, "opacity": OBSTACLE_OPACITY}
        if isinstance(s, Box):
            server.scene.add_box(name, dimensions=s.size, **look, **pose)
        elif isinstance(s, Sphere):
            server.scene.add_icosphere(name, radius=s.radius, **look, **pose)
        else:
            vertices, faces = (cylinder_mesh(s.radius, s.length) if isinstance(s, CylinderShape)
                               else (s.vertices, s.faces))
            server.scene.add_mesh_simple(name, np.asarray(vertices, np.float32),
                                         np.asarray(faces, np.uint32), flat_shading=True,
                                         side="double", **look, **pose)


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Silence viser's unconditional banner (it writes to sys.stdout via rich)."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield


@dataclass
class ReplayServer:
    """A running replay page. ``url`` to open; :meth:`stop` ends it; :meth:`wait` blocks."""

    url: str
    server: Any
    _stop: threading.Event = field(default_factory=threading.Event)
    _thread: threading.Thread | None = None

    def stop(self) -> None:
        """Stop the player thread and the web server (frees the port); safe to call twice."""
        if self._stop.is_set():
            return
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        with quiet():
            self.server.stop()

    def every(self, period: float, step: Callable[[], None], name: str) -> None:
        """Run ``step`` every ``period`` s in a background thread named ``name``, until
        :meth:`stop` (which joins it)."""
        def run() -> None:
            while not self._stop.wait(period):
                step()

        self._thread = threading.Thread(target=run, name=name, daemon=True)
        self._thread.start()

    def wait(self) -> None:
        """Serve until :meth:`stop` is called from another thread or Ctrl-C."""
        try:
            while not self._stop.wait(0.5):
                pass
        except KeyboardInterrupt:
            self.stop()

    def __enter__(self) -> ReplayServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()




def add_ground(server: Any) -> None:
    """z up, a 6 m grid on the floor (0.25 m cells, 1 m sections), and the default lights
    without viser's image-based environment: a browser without a GPU (software WebGL) took
    minutes to light the scene from the environment image, showing it faded until then."""
    server.scene.set_up_direction("+z")
    server.scene.configure_environment_map(hdri=None)
    server.scene.add_grid("/ground", width=6.0, height=6.0, cell_size=0.25, section_size=1.0,
                          position=(0.0, 0.0, 0.001))
