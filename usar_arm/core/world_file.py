"""A world file's scenery (walls, furniture, obstacles), read without the simulator.

World files (YAML) hold a floor height, named start poses and boxes, in metres and radians in
the USARSim frame (x forward, y right, z down; a box on the floor has a negative centre z). The
embedded simulator (``usar_arm.sim.world_spec``) reads the whole file with this module; pictures
and checks that only need the scenery read it here, so they never load the simulator. The
shipped worlds (``default``, ``rooms``) are data files beside the simulator's package.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from usar_arm.core.errors import FileFormatError
from usar_arm.core.named_file import resolve_name

WORLDS_PACKAGE = "usar_arm.sim"
"""The package whose ``worlds/`` folder holds the shipped world files (data only: reading it
imports no simulator module besides that package's lazy ``__init__``)."""


@dataclass(frozen=True)
class SceneryBox:
    """A static box of the world: name, centre (m), half sizes (m), yaw about z (rad); USARSim
    frame (z down)."""

    name: str
    center: tuple[float, float, float]
    half: tuple[float, float, float]
    yaw: float = 0.0

    def corners_xy(self) -> tuple[tuple[float, float], ...]:
        """The four corners of the box's footprint (m, USARSim x, y), counter-clockwise in
        that frame's top view."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        hx, hy = self.half[0], self.half[1]
        return tuple((self.center[0] + c * px - s * py, self.center[1] + s * px + c * py)
                     for px, py in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)))


@dataclass(frozen=True)
class Scenery:
    """What a world file says about the space: its boxes and the floor height (m, z down)."""

    boxes: tuple[SceneryBox, ...]
    floor_z: float = 0.0


def shipped_worlds() -> tuple[str, ...]:
    """The names of the world files shipped with the simulator (``default``, ``rooms``)."""
    folder = resources.files(WORLDS_PACKAGE) / "worlds"
    return tuple(sorted(e.name[:-5] for e in folder.iterdir() if e.name.endswith(".yaml")))


def read_world_file(path: str | Path | None = None) -> tuple[str, dict[str, Any]]:
    """The world file's name (as given) and its YAML mapping; a shipped world by name
    (default: ``default``; a name or a path by :mod:`usar_arm.core.named_file`'s rule).

    Raises:
        FileFormatError: no such world (what was tried), or the file is not YAML or not a
            mapping.
    """
    named = resolve_name("default" if path is None else path, "world", shipped_worlds())
    if named.shipped is not None:
        with resources.as_file(resources.files(WORLDS_PACKAGE) / "worlds"
                               / f"{named.shipped}.yaml") as fp:
            return read_world_file(fp)
    name = named.given
    try:
        data = yaml.safe_load(Path(name).read_text())
    except yaml.YAMLError as exc:
        raise FileFormatError(name, f"not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise FileFormatError(name, "expected a mapping with start_poses and boxes")
    return name, data


def load_scenery(path: str | Path | None = None) -> Scenery:
    """The boxes and floor of a world file, or of a shipped world by name.

    Raises:
        FileFormatError: no such world, or the file is not a world file.
    """
    name, data = read_world_file(path)
    return Scenery(parse_boxes(data.get("boxes") or [], name), float(data.get("floor_z", 0.0)))


def parse_boxes(entries: list[Any], path: str) -> tuple[SceneryBox, ...]:
    """The ``boxes`` list of a world file, checked (``path`` names the file in errors)."""
    out = []
    for i, b in enumerate(entries):
        try:
            center = tuple(float(v) for v in b["center"])
            half = tuple(float(v) for v in b["half"])
            yaw = float(b.get("yaw", 0.0))
        except (KeyError, TypeError, ValueError, AttributeError):
            raise FileFormatError(path, "expected center [x,y,z], half [hx,hy,hz] and an "
                                  "optional yaw", field=f"boxes[{i}]") from None
        if len(center) != 3 or len(half) != 3 or min(half) <= 0:
            raise FileFormatError(path, "center and half need three numbers, half sizes > 0",
                                  field=f"boxes[{i}]")
        if not all(math.isfinite(v) for v in (*center, *half, yaw)):
            raise FileFormatError(path, "numbers must be finite", field=f"boxes[{i}]")
        out.append(SceneryBox(str(b.get("name", f"box{i}")), center, half,  # type: ignore[arg-type]
                              yaw))
    return tuple(out)
