"""A WorldController client: a connection that INITs as ``USARBotAPI.WorldController`` and
creates, moves, destroys and lists the objects of a physical cell with CONTROL.

UDK answers no CONTROL but GetSTA, so every command here that changes the world checks itself
with GetSTA (``confirm=True``, the default) and raises
:class:`~usar_arm.core.cell_errors.WorldControllerError` naming what it expected and what GetSTA
showed (an unknown class, a duplicate name and a spawn inside geometry all look the same: no
object). GetSTA's reply names no class: :meth:`WorldControllerClient.sightings` asks once per
class (``{ClassName ..}`` filters by class) to tell them apart. Vectors are sent in the wire's
frame (x forward, y right, z down; metres, roll/pitch/yaw radians). Note UDK's
``cleanOnClose``: closing this connection destroys every non-permanent object.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

from usar_arm.core.cell import Sighting
from usar_arm.core.cell_errors import WorldControllerError
from usar_arm.core.errors import ConnectionLostError, ResponseTimeoutError
from usar_arm.core.spatial import rpy_to_matrix, transform
from usar_arm.core.wc_classes import WC_CLASSES, find_class
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.exchange import Exchange
from usar_arm.usarsim.numbers import FULL

CLASS_NAME = "USARBotAPI.WorldController"
POLL_S = 0.05
"""Seconds between the GetSTA polls of a confirmation."""


def vector_text(v: Sequence[float]) -> str:
    """``x,y,z`` at full precision (what UDK's ParseVector reads)."""
    return FULL.raw_vector(v)


class WorldControllerClient(Exchange):
    """A WorldController connection (use as a context manager, or :meth:`connect` and
    :meth:`close`). Args as :class:`~usar_arm.usarsim.exchange.Exchange`'s, plus ``name``."""

    def __init__(self, host: str = "127.0.0.1", port: int = 3000, timeout: float = 5.0,
                 name: str = "WorldController"):
        super().__init__(host, port, timeout)
        self.name = name

    def connect(self) -> m.GameInfo:
        """Open the connection, wait for the greeting, and INIT as a WorldController."""
        self._wire.open(self.connect_timeout)
        with self._cond:
            self._cond.wait_for(lambda: self._inbox.game_info is not None
                                or self._wire.closed_reason is not None, self.connect_timeout)
        info = self._inbox.game_info
        if info is None:
            self.close()
            if self._wire.closed_reason is not None:
                raise ConnectionLostError("waiting for the NFO greeting",
                                          self._wire.closed_reason)
            raise ResponseTimeoutError("NFO greeting", self.connect_timeout,
                                       f"{self.host}:{self.port} accepted the connection")
        self.send(m.Init(CLASS_NAME, self.name))
        return info

    def close(self) -> None:
        """Close the connection (UDK's cleanOnClose then destroys the non-permanent objects)."""
        self._wire.close()

    def __enter__(self) -> WorldControllerClient:
        if self._wire.local_port is None:
            self.connect()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ commands
    def get_sta(self, class_name: str = "", name: str = "", timeout: float | None = None
                ) -> m.WcStatus:
        """``CONTROL {Type GetSTA} [{ClassName c}] [{Name n}]``: this controller's objects
        (of class ``c`` or a subclass, called exactly ``n``)."""
        msg = m.Control("GetSTA", name=name or None, class_name=class_name or None)
        rec = self.request(msg, lambda x: isinstance(x, m.WcStatus), timeout)
        assert isinstance(rec.message, m.WcStatus), "accepted only a GetSTA reply"
        return rec.message

    def create(self, name: str, class_name: str, location: Sequence[float],
               rotation: Sequence[float] = (0.0, 0.0, 0.0),
               scale: Sequence[float] = (1.0, 1.0, 1.0), physics: str = "RigidBody",
               permanent: bool = False, memory: str = "", material: str = "",
               confirm: bool = True, timeout: float | None = None) -> m.WcObjectStatus | None:
        """``CONTROL {Type Create}``: an object of ``class_name`` (``WCCrate`` means
        ``USARPhysObj.WCCrate``) at ``location`` (m) and ``rotation`` (rad); ``physics`` other
        than RigidBody, Falling or Ground makes it static. With ``confirm``, waits until
        GetSTA lists it and returns its status (None without); a name this controller already
        uses (any case) is refused at once, after the command was sent (UDK logs it)."""
        taken = self.get_sta(timeout=timeout) if confirm else None
        self.send(m.Control("Create", name=name, class_name=class_name,
                            location=vector_text(location), rotation=vector_text(rotation),
                            scale=vector_text(scale), physics=physics,
                            permanent="true" if permanent else "false",
                            memory=memory or None, material=material or None))
        if taken is None:
            return None
        command = f"Create {name} ({class_name})"
        same = [o.name for o in taken.objects if o.name.upper() == name.upper()]
        if same:
            raise WorldControllerError(command, f"no object called '{name}' before it",
                                       ", ".join(o.name for o in taken.objects),
                                       f"'{same[0]}' already exists: UDK refuses the name")
        return self._until(command, f"an object called '{name}'", lambda s: s.find(name),
                           timeout, "an unknown class, a name already taken (any case) or a "
                           "spawn inside existing geometry")

    def kill(self, name: str, confirm: bool = True, timeout: float | None = None) -> None:
        """``CONTROL {Type Kill} {Name n}`` (the name in any case)."""
        self.send(m.Control("Kill", name=name))
        if confirm:
            self._until(f"Kill {name}", f"no object called '{name}'",
                        lambda s: not any(o.name.upper() == name.upper() for o in s.objects),
                        timeout)

    def kill_all(self, min_pos: Sequence[float] | None = None,
                 max_pos: Sequence[float] | None = None, confirm: bool = True,
                 timeout: float | None = None) -> None:
        """``CONTROL {Type KillAll} [{MinPos ..} {MaxPos ..}]``: every non-permanent object,
        or those strictly inside the box (UDK compares z negated: inside means
        ``max_pos.z < z < min_pos.z`` in the wire's z-down metres)."""
        box = min_pos is not None and max_pos is not None
        self.send(m.Control("KillAll", min_pos=vector_text(min_pos) if box and min_pos else None,
                            max_pos=vector_text(max_pos) if box and max_pos else None))
        if confirm:  # KillAll's effect is checked by the next GetSTA (commands run in order)
            self.get_sta(timeout=timeout)

    def abs_move(self, name: str, location: Sequence[float],
                 rotation: Sequence[float] = (0.0, 0.0, 0.0), confirm: bool = True,
                 timeout: float | None = None) -> None:
        """``CONTROL {Type AbsMove}``: teleport an object (or a robot, by its INIT name)."""
        self.send(m.Control("AbsMove", name=name, location=vector_text(location),
                            rotation=vector_text(rotation)))
        if confirm:
            self.get_sta(timeout=timeout)

    def rel_move(self, name: str, location: Sequence[float],
                 rotation: Sequence[float] = (0.0, 0.0, 0.0), confirm: bool = True,
                 timeout: float | None = None) -> None:
        """``CONTROL {Type RelMove}``: move an object (or a robot) by an offset."""
        self.send(m.Control("RelMove", name=name, location=vector_text(location),
                            rotation=vector_text(rotation)))
        if confirm:
            self.get_sta(timeout=timeout)

    def _until(self, command: str, expected: str, test: Callable[[m.WcStatus], object],
               timeout: float | None, hint: str = "") -> m.WcObjectStatus | None:
        """Poll GetSTA until ``test`` holds (its result, when it is an object's status)."""
        limit = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + limit
        while True:
            status = self.get_sta(timeout=max(0.1, deadline - time.monotonic()))
            result = test(status)
            if result:
                return result if isinstance(result, m.WcObjectStatus) else None
            if time.monotonic() >= deadline:
                seen = ", ".join(o.name for o in status.objects) or "no objects"
                raise WorldControllerError(command, expected, seen, hint)
            time.sleep(POLL_S)

    # ------------------------------------------------------------------ what is there
    def sightings(self, classes: Sequence[str] = tuple(WC_CLASSES),
                  timeout: float | None = None) -> list[Sighting]:
        """Every object of this controller with its class: one GetSTA for all and one per
        class of ``classes`` (the reply names no class); an object no class lists is left
        out (a class this client does not know)."""
        everything = self.get_sta(timeout=timeout)
        of_class: dict[str, str] = {}
        for cls in classes:
            for obj in self.get_sta(class_name=cls, timeout=timeout).objects:
                of_class.setdefault(obj.name, cls)
        out = []
        for obj in everything.objects:
            known = find_class(of_class.get(obj.name, ""))
            if known is not None:
                pose = transform(rpy_to_matrix(obj.rotation), obj.location)
                out.append(Sighting(obj.name, known, pose, obj.size, obj.memory))
        return out
