"""The simulator's world ("map"): game info and named start poses, loaded from YAML."""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import yaml

from usar_arm.core.errors import FileFormatError
from usar_arm.usarsim.messages import StartPose


@dataclass(frozen=True)
class WorldSpec:
    """What NFO and GETSTARTPOSES report; start poses in metres/radians, z-down frame."""

    gametype: str
    level: str
    time_limit: float
    start_poses: tuple[StartPose, ...]

    def find_start(self, name: str) -> StartPose | None:
        """The start pose whose tag matches ``name`` case-insensitively (as UDK does)."""
        for pose in self.start_poses:
            if pose.name.lower() == name.lower():
                return pose
        return None


def load_world(path: str | Path | None = None) -> WorldSpec:
    """Load a world file (default: the shipped ``worlds/default.yaml``)."""
    if path is None:
        with resources.as_file(resources.files("usar_arm.sim") / "worlds" / "default.yaml") as fp:
            return load_world(fp)
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
                     float(data.get("time_limit", 0)), tuple(poses))
