"""An interactive 3D view of a reachability map in a web browser (viser, the ``viz`` extra):
the marked voxels as a point cloud coloured by their index, a slider that hides voxels below an
index, the arm at its zero configuration and the scene's obstacles. Lengths in m."""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from matplotlib import colormaps
from numpy.typing import NDArray

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


def _cloud(index: NDArray[np.floating[Any]], origin: Array, resolution: float, floor: float
           ) -> tuple[NDArray[np.float32], NDArray[np.uint8]]:
    """Centres (k, 3) float32 and colours (k, 3) uint8 of the voxels with index >= floor."""
    ijk = np.argwhere(index >= max(floor, 1e-9))
    values = index[tuple(ijk.T)]
    colours = (colormaps["viridis"](values)[:, :3] * 255).astype(np.uint8)
    return (origin + ijk * resolution).astype(np.float32), colours


def serve_reach(urdf_text: str, index: NDArray[np.floating[Any]], origin: Array, resolution: float,
                scene: Scene | None = None, host: str = "127.0.0.1", port: int = 8080
                ) -> ReplayServer:
    """Serve the view (returns at once; ``wait()`` blocks until Ctrl-C, ``stop()`` ends it).

    Args:
        index: (nx, ny, nz) reachability index. origin: (3,) m, the centre of voxel
            (0, 0, 0). resolution: m.
    """
    viser = load_viser()
    with quiet():
        server = viser.ViserServer(host=host, port=port, verbose=False)
    try:
        add_ground(server)
        if scene is not None:
            add_obstacles(server, scene)
        viser.extras.ViserUrdf(server, load_urdf(urdf_text), root_node_name="/arm")
        points, colours = _cloud(index, origin, resolution, 0.0)
        cloud: dict[str, Any] = {"handle": server.scene.add_point_cloud(
            "/reach", points, colours, point_size=resolution * 0.5)}
        floor = server.gui.add_slider("Smallest index shown", min=0.0, max=1.0, step=0.05,
                                      initial_value=0.0)
        server.gui.add_markdown(f"**{len(points):,} voxels reached**, {resolution * 100:g} cm; "
                                "colour: fraction of orientations reached")

        def refilter(_event: object) -> None:
            cloud["handle"].remove()
            pts, cols = _cloud(index, origin, resolution, float(floor.value))
            cloud["handle"] = server.scene.add_point_cloud("/reach", pts, cols,
                                                           point_size=resolution * 0.5)

        floor.on_update(refilter)
        server.initial_camera.look_at = (0.0, 0.0, 0.8)
        server.initial_camera.position = (4.0, -5.0, 3.0)
    except BaseException:
        with quiet():
            server.stop()
        raise
    handle = ReplayServer(f"http://{host}:{server.get_port()}", server)
    log.info("reachability map served at %s", handle.url)
    return handle
