"""The simulator's world ("map"): game info, named start poses and scenery, loaded from YAML.

The scenery is a flat floor (a plane at ``floor_z``, z down, so the ground is at z = 0 by default)
and boxes: walls, furniture, obstacles, each a centre, half sizes and a yaw, all in metres and
radians in the USARSim frame (x forward, y right, z down; a box standing on the floor has a
negative centre z); and, with ``cell: <name or file>``, a work cell's static pieces
(:mod:`usar_arm.core.cell`: the one description the planner reads too, in REP-103 at the world
origin). Ground vehicles drive on the floor and collide with the boxes; the range scanner sees
them; arms, tools and WorldController objects collide with all of it.

The file format and the scenery are read by :mod:`usar_arm.core.world_file`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from usar_arm.core.cell import StaticPiece, load_cell
from usar_arm.core.errors import FileFormatError
from usar_arm.core.world_file import SceneryBox, parse_boxes, read_world_file, shipped_worlds
from usar_arm.usarsim.messages import StartPose


@dataclass(frozen=True)
class WorldSpec:
    """What NFO and GETSTARTPOSES report (start poses in metres/radians, z-down frame) and the
    scenery the physics holds."""

    gametype: str
    level: str
    time_limit: float
    start_poses: tuple[StartPose, ...]
    boxes: tuple[SceneryBox, ...] = ()
    floor_z: float = 0.0
    cell: tuple[StaticPiece, ...] = ()
    """A work cell's static pieces (REP-103, the cell's frame at the world origin)."""
    cell_name: str = ""

    def find_start(self, name: str) -> StartPose | None:
        """The start pose whose tag matches ``name`` case-insensitively (as UDK does)."""
        for pose in self.start_poses:
            if pose.name.lower() == name.lower():
                return pose
        return None


def load_world(path: str | Path | None = None) -> WorldSpec:
    """Load a world file, or a shipped world by name (default: ``default``, the arms' cell).

    Raises:
        FileFormatError: the file is not a world file.
        FileNotFoundError: no such file and no shipped world of that name.
    """
    p, data = read_world_file(path)
    poses = []
    for i, sp in enumerate(data.get("start_poses", [])):
        try:
            loc = tuple(float(v) for v in sp["location"])
            rot = tuple(float(v) for v in sp["rotation"])
        except (KeyError, TypeError, ValueError):
            raise FileFormatError(p, "expected name, location [x,y,z], rotation [r,p,y]",
                                  field=f"start_poses[{i}]") from None
        if len(loc) != 3 or len(rot) != 3:
            raise FileFormatError(p, "location and rotation need three numbers",
                                  field=f"start_poses[{i}]")
        poses.append(StartPose(str(sp["name"]), loc, rot))  # type: ignore[arg-type]
    cell_name = data.get("cell")
    if cell_name is not None and not isinstance(cell_name, str):
        raise FileFormatError(p, f"expected a cell's name or file, got {cell_name!r}",
                              field="cell")
    cell = load_cell(cell_name).static if cell_name else ()
    return WorldSpec(str(data.get("gametype", "BotDeathMatch")), str(data.get("level", "")),
                     float(data.get("time_limit", 0)), tuple(poses),
                     parse_boxes(data.get("boxes") or [], p), float(data.get("floor_z", 0.0)),
                     cell, cell_name or "")


__all__ = ["SceneryBox", "WorldSpec", "load_world", "shipped_worlds"]
