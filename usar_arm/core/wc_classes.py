"""The object classes a USARSim WorldController spawns (``USARPhysObj.WC*``): sizes and masses.

UDK's classes name a static mesh and a mass (``WCCrate.uc``: ``Mesh=StaticMesh'WCObjectPkg.
Crates.Crate'``, ``Mass = 5.0``); the cooked meshes are not in UDK's repository, so the sizes
here are usar-arm's choice (plausible ones, docs/simulator.md), the masses are the ``.uc`` ones.
Spawned with ``{Scale sx,sy,sz}``, an object's sizes scale per axis and its mass by the product
of the three (``WCObject.Init``: ``SetMass(self, Mass * scale.X * scale.Y * scale.Z)``).

Every object's origin (the ``{Location}`` of CONTROL and GetSTA) is the centre of its bounding
box. A solid class is one box; an open container (a bin, a kit tray) is a floor and four walls,
open at the top (-z of the USARSim frame, +z of REP-103), so that a part can be put *in* it.
Shapes here are in REP-103 axes of the object's frame (z up), metres.
"""

from __future__ import annotations

from dataclasses import dataclass

PACKAGE = "USARPhysObj"
"""The package an unqualified class name is taken from (``WorldController.Create``)."""


@dataclass(frozen=True)
class WcClass:
    """A WorldController object class.

    Attributes:
        name: the class name without its package (``WCCrate``).
        size: outer edge lengths x, y, z (m) at scale 1.
        mass: the ``.uc`` mass (kg) at scale 1.
        wall: wall and floor thickness (m) of an open container; 0 for a solid box.
    """

    name: str
    size: tuple[float, float, float]
    mass: float
    wall: float = 0.0

    @property
    def full_name(self) -> str:
        """``USARPhysObj.WCCrate``."""
        return f"{PACKAGE}.{self.name}"

    @property
    def is_container(self) -> bool:
        """True for an open container (floor and walls)."""
        return self.wall > 0.0

    def boxes(self, scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
              ) -> tuple[tuple[str, tuple[float, float, float], tuple[float, float, float]], ...]:
        """The class's boxes at ``scale``: (piece name, centre (m), edge lengths (m)) in the
        object's frame, REP-103 axes (z up): ``("body", ...)`` for a solid box; ``floor``,
        ``wall_front`` (+x), ``wall_back``, ``wall_left`` (+y), ``wall_right`` for a container.
        Walls and floor scale with the object, as UDK's draw scale scales the whole mesh."""
        sx, sy, sz = (self.size[i] * scale[i] for i in range(3))
        if not self.is_container:
            return (("body", (0.0, 0.0, 0.0), (sx, sy, sz)),)
        tx, ty, tz = (self.wall * scale[i] for i in range(3))
        wall_z = (tz / 2, sz - tz)  # walls stand on the floor
        return (("floor", (0.0, 0.0, -sz / 2 + tz / 2), (sx, sy, tz)),
                ("wall_front", (sx / 2 - tx / 2, 0.0, wall_z[0]), (tx, sy, wall_z[1])),
                ("wall_back", (-sx / 2 + tx / 2, 0.0, wall_z[0]), (tx, sy, wall_z[1])),
                ("wall_left", (0.0, sy / 2 - ty / 2, wall_z[0]), (sx - 2 * tx, ty, wall_z[1])),
                ("wall_right", (0.0, -sy / 2 + ty / 2, wall_z[0]), (sx - 2 * tx, ty, wall_z[1])))

    def scaled_mass(self, scale: tuple[float, float, float]) -> float:
        """The mass (kg) at ``scale``: the class mass times the scale's product."""
        return self.mass * scale[0] * scale[1] * scale[2]


WC_CLASSES: dict[str, WcClass] = {c.name: c for c in (
    WcClass("WCCrate", (0.30, 0.30, 0.25), 5.0),
    WcClass("WCCrateRed", (0.30, 0.30, 0.25), 5.0),
    WcClass("WCCrateGreen", (0.30, 0.30, 0.25), 5.0),
    WcClass("WCCrateBlue", (0.30, 0.30, 0.25), 5.0),
    WcClass("WCKivaPallet", (0.30, 0.30, 0.25), 0.1),  # the crate's mesh, WCObject's mass
    WcClass("WCObjectBin", (0.40, 0.30, 0.20), 10.0, wall=0.015),
    WcClass("WCKitTray", (0.50, 0.35, 0.05), 5.0, wall=0.01),
    WcClass("WCKitTraySmall", (0.30, 0.20, 0.04), 5.0, wall=0.01),
    WcClass("WCPallet", (1.20, 0.80, 0.144), 18.0),  # a EUR pallet's outline, as one block
)}
"""The simulated classes by name (without the package)."""


def find_class(name: str) -> WcClass | None:
    """The class ``USARPhysObj.<name>`` (or ``name`` alone) names, matched without regard to
    case as Unreal's class lookup is; None for any other package or an unknown class."""
    package, _, short = name.rpartition(".")
    if package and package.lower() != PACKAGE.lower():
        return None
    for cls in WC_CLASSES.values():
        if cls.name.lower() == short.lower():
            return cls
    return None
