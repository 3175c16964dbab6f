"""The lines of a physical cell: the WorldController's CONTROL commands and its GetSTA reply
(UDK), and usar-arm's truth extensions beside them (which vacuum holds what, which bodies touch).

Field names follow the protocol keys; units are the wire's (metres and radians in the USARSim
z-down frame, seconds of simulated time). Re-exported by :mod:`usar_arm.usarsim.messages`; their
text forms are :mod:`usar_arm.usarsim.cell_codec`'s.
"""

from __future__ import annotations

from dataclasses import dataclass

Vector3 = tuple[float, float, float]
Block = tuple[str, str]


@dataclass(frozen=True)
class Control:
    """``CONTROL {Type T} [{Name n}] ...``: a WorldController command (``BotConnection.uc
    ProcessWorldController``).

    Values are kept as the text UDK reads, because UDK parses each one leniently itself
    (``Utilities.ParseVector``: a missing component reads 0, a word reads 0): a vector is
    ``x,y,z`` (metres, or roll,pitch,yaw radians). ``type`` is compared case-sensitively
    (``Create``, ``Kill``, ``KillAll``, ``AbsMove``, ``RelMove``, ``GetSTA``...).
    """

    type: str
    name: str | None = None
    class_name: str | None = None
    location: str | None = None
    rotation: str | None = None
    scale: str | None = None
    physics: str | None = None
    permanent: str | None = None
    memory: str | None = None
    material: str | None = None
    start: str | None = None
    min_pos: str | None = None
    max_pos: str | None = None
    extra: tuple[Block, ...] = ()


@dataclass(frozen=True)
class WcObjectStatus:
    """One object of a GetSTA reply: name, the size of its world-axis bounding box (m), where
    its origin is (m), its Memory text and its rotation (roll, pitch, yaw rad)."""

    name: str
    size: Vector3
    location: Vector3
    memory: str
    rotation: Vector3


@dataclass(frozen=True)
class WcStatus:
    """The reply to ``CONTROL {Type GetSTA}``, exactly UDK's (``WorldController.GetSTA``)::

        STA {Name n} {Size sx,sy,sz} {Location x,y,z {Memory {m} {Rotation r,p,y}

    per object, with ``{Location`` never closed and Memory wrapped in an extra brace pair; no
    object at all is the bare word ``STA``. The class of an object is not in it (ask with
    ``{ClassName ..}``, which filters by class and its subclasses).
    """

    objects: tuple[WcObjectStatus, ...] = ()

    def find(self, name: str) -> WcObjectStatus | None:
        """The object called ``name`` (exactly, as GetSTA's name filter compares)."""
        return next((o for o in self.objects if o.name == name), None)


@dataclass(frozen=True)
class ContactPair:
    """Two bodies that touched (an extension): their names (``link:<robot>/<part>``,
    ``tool:<robot>/<tool>``, ``object:<name>``, ``scenery:<name>``), the first and last
    simulated time (s) of the contact in the report's window, its deepest penetration (m)
    and the number of physics steps it lasted."""

    a: str
    b: str
    first: float
    last: float
    depth: float
    steps: int = 1


@dataclass(frozen=True)
class ContactReport:
    """``SEN {Time t} {Type Contact} {Name <robot>} {Count n} {Pair a b} {First ..} {Last ..}
    {Depth ..} {Steps ..} ...``: a robot's contacts since its previous report (an extension,
    at every status, 10 Hz), or ``{Count 0}``."""

    name: str
    pairs: tuple[ContactPair, ...] = ()
    time: float | None = None
    type: str = "Contact"


@dataclass(frozen=True)
class GripTruth:
    """``SEN {Time t} {Type GripTruth} {Name <vacuum>} {Holding True|False} [{Object name}]``:
    whether a vacuum really holds an object, and which (an extension beside UDK's EFF, whose
    CLOSED says only that the vacuum is on)."""

    name: str
    holding: bool
    object: str | None = None
    time: float | None = None
    type: str = "GripTruth"
    extra: tuple[Block, ...] = ()
