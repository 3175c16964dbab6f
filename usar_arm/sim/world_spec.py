"""The simulator's world ("map"): game info, named start poses and scenery, loaded from YAML.

The scenery is a flat floor (a plane at ``floor_z``, z down, so the ground is at z = 0 by default)
and boxes: walls, furniture, obstacles, each a centre, half sizes and a yaw, all in metres and
radians in the USARSim frame (x forward, y right, z down; a box standing on the floor has a
negative centre z). Ground vehicles drive on the floor and collide with the boxes; the range
scanner sees them; the arms ignore both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from usar_arm.core.errors import FileFormatError
from usar_arm.usarsim.messages import StartPose


@dataclass(frozen=True)
class SceneryBox:
    """A static box of the world: name, centre (m), half sizes (m), yaw about z (rad)."""

    name: str
    center: tuple[float, float, float]
    half: tuple[float, float, float]
    yaw: float = 0.0


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

    def find_start(self, name: str) -> StartPose | None:
        """The start pose whose tag matches ``name`` case-insensitively (as UDK does)."""
        for pose in self.start_poses:
            if pose.name.lower() == name.lower():
                return pose
        return None


def shipped_worlds() -> tuple[str, ...]:
    """The names of the world files shipped with the simulator (``default``, ``rooms``)."""
    folder = resources.files("usar_arm.sim") / "worlds"
    return tuple(sorted(e.name[:-5] for e in folder.iterdir() if e.name.endswith(".yaml")))


def load_world(path: str | Path | None = None) -> WorldSpec:
    """Load a world file, or a shipped world by name (default: ``default``, the arms' cell).

    Raises:
        FileFormatError: the file is not a world file.
        FileNotFoundError: no such file and no shipped world of that name.
    """
    name = "default" if path is None else str(path)
    if path is None or (name in shipped_worlds() and not Path(name).exists()):
        with resources.as_file(resources.files("usar_arm.sim") / "worlds" / f"{name}.yaml") as fp:
            return load_world(fp)
    if not Path(path).is_file():
        raise FileNotFoundError(f"no world file {name} (shipped worlds: "
                                f"{', '.join(shipped_worlds())})")
    p = str(path)
    try:
        data = yaml.safe_load(Path(path).read_text())
    except yaml.YAMLError as exc:
        raise FileFormatError(p, f"not valid YAML: {exc}") from None
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
    return WorldSpec(str(data.get("gametype", "BotDeathMatch")), str(data.get("level", "")),
                     float(data.get("time_limit", 0)), tuple(poses),
                     _boxes(data.get("boxes") or [], p), float(data.get("floor_z", 0.0)))


def _boxes(entries: list[Any], path: str) -> tuple[SceneryBox, ...]:
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
