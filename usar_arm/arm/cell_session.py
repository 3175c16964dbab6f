"""A physical cell on a USARSim server, through a WorldController connection of its own: built
from the cell's description (``CONTROL Create`` of each object it spawns), read back as the
planner's scene (GetSTA: what is really there), and asked where an object is.

The robot stands at RobotStart1, the world origin: the cell's frame is its base_link (REP-103,
z up); the wire's is z down (x, -y, -z). Closing the connection destroys the objects it made
unless they were made permanent (UDK's ``cleanOnClose``): a run against a server the user
started keeps them, for inspection.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from usar_arm.core.cell import Cell, load_cell
from usar_arm.core.spatial import (
    Array,
    matrix_to_rpy,
    rpy_to_matrix,
    transform,
    zdown_to_zup_transform,
)
from usar_arm.planning.cell_scene import scene_from_sightings
from usar_arm.planning.scene import Scene
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.world_controller import WorldControllerClient

log = logging.getLogger("usar_arm.arm.cell_session")


class CellSession:
    """A cell built on a server.

    Args:
        host, port: the server. cell: a cell description (a shipped name such as ``table``, a
            path, or a loaded :class:`~usar_arm.core.cell.Cell`). permanent: create the
            objects permanent (they outlive this connection). timeout: s per GetSTA.
    """

    def __init__(self, host: str, port: int, cell: str | Cell = "table",
                 permanent: bool = False, timeout: float = 5.0):
        self.cell = cell if isinstance(cell, Cell) else load_cell(cell)
        self.permanent = permanent
        self.wc = WorldControllerClient(host, port, timeout=timeout)
        self.wc.connect()

    def close(self) -> None:
        """Close the WorldController's connection (non-permanent objects go with it)."""
        self.wc.close()

    def __enter__(self) -> CellSession:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def build(self) -> list[str]:
        """Create every object the cell spawns, each confirmed by GetSTA; an object of the same
        name left by an earlier run (a permanent one) is destroyed first. Returns the names.

        Raises:
            WorldControllerError: an object was not created (names what GetSTA shows: a spawn
                inside existing geometry, or a class the server does not know).
        """
        present = {o.name.upper() for o in self.wc.get_sta().objects}
        made = []
        for p in self.cell.spawn:
            if p.name.upper() in present:
                log.info("destroying the %s an earlier run left", p.name)
                self.wc.kill(p.name)
            wire = zdown_to_zup_transform(p.pose)  # (the flip is its own inverse)
            self.wc.create(p.name, p.wc_class.name, wire[:3, 3].tolist(),
                           matrix_to_rpy(wire[:3, :3]),
                           p.scale, p.physics, permanent=self.permanent or p.permanent,
                           memory=p.memory, material=p.material)
            made.append(p.name)
        return made

    def scene(self, name: str = "simulator") -> Scene:
        """The planner's scene of what the server reports now: the cell's static scenery and
        every WorldController object by its class and GetSTA pose."""
        return scene_from_sightings(self.wc.sightings(), self.cell, name=name)

    def status(self, name: str) -> m.WcObjectStatus | None:
        """GetSTA of the object called ``name`` (None: no such object)."""
        return self.wc.get_sta(name=name).find(name)

    def pose(self, name: str) -> Array | None:
        """The pose (4x4, base_link: REP-103, m) of the object called ``name``, by GetSTA."""
        found = self.status(name)
        if found is None:
            return None
        wire = transform(rpy_to_matrix(found.rotation), found.location)
        out: Array = zdown_to_zup_transform(wire)
        return out

    def resting(self, name: str, seconds: float = 0.3, still_m: float = 1e-3) -> Array | None:
        """The object's pose once two GetSTA ``seconds`` apart agree within ``still_m`` (m),
        after at most 3 s; None when there is no such object."""
        last = self.pose(name)
        deadline = time.monotonic() + 3.0
        while last is not None and time.monotonic() < deadline:
            time.sleep(seconds)
            now = self.pose(name)
            if now is None or float(np.linalg.norm(now[:3, 3] - last[:3, 3])) <= still_m:
                return now
            last = now
        return last
