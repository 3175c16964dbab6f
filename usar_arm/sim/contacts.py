"""Contacts as ground truth: which bodies touched, when and how deeply (an extension; UDK
reports no contacts at all).

After every physics step the contacts MuJoCo found are read as arrays; those that touch a
*robot part* (an arm link or a tool) or an object a vacuum holds are kept, per robot involved
and per pair of bodies, as the first and last simulated time of the pair's contact and its
deepest penetration since the robot's previous report, so that a contact lasting one physics
step between two status lines is never lost. Objects resting on the scenery or on each other
are not robot contacts and are not kept. Only the kept contacts (few, usually none) are
visited in Python; the rest is one array lookup per step.

Bodies are named by kind: ``link:<robot>/<part>``, ``tool:<robot>/<tool>``, ``object:<name>``
(a WorldController object), ``scenery:<name>`` (the floor, a world file's box, a cell's piece).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from usar_arm.sim import mj
from usar_arm.sim.scenery import BOX_PREFIX, CELL_PREFIX
from usar_arm.usarsim.messages import ContactPair

HISTORY = 10_000
"""Reported contact records each robot keeps for the in-process truth (the latest)."""


@dataclass
class Entity:
    """A body that can touch: its report name, the robot it belongs to (the holding robot for a
    held object; "" for none) and whether its contacts are kept."""

    name: str
    robot: str
    kept: bool


class ContactLog:
    """The contacts of every robot since its last report."""

    def __init__(self) -> None:
        self.entities: list[Entity] = []
        self._geom_entity = np.zeros(0, dtype=np.int32)
        self._kept = np.zeros(0, dtype=bool)
        self._open: dict[str, dict[tuple[int, int], list[float]]] = {}
        self._history: dict[str, deque[ContactPair]] = {}
        self._object_entity: dict[int, int] = {}

    def index(self, m: mj.Model, names: dict[int, tuple[str, str, bool]]) -> None:
        """Name every geom's body after a rebuild. ``names``: body id -> (report name, robot
        key, kept) for every body that is not the world; world geoms are scenery. Contacts
        still open are carried over by report name."""
        old = [e.name for e in self.entities]
        self.entities, by_name = [], {}
        geom_entity = np.zeros(m.ngeom, dtype=np.int32)
        for g in range(m.ngeom):
            body = int(m.geom_bodyid[g])
            if body == 0:
                name = _scenery_name(mj.id_name(m, "geom", g))
                robot, kept = "", False
            else:
                name, robot, kept = names.get(body, (f"body:{mj.id_name(m, 'body', body)}", "",
                                                     False))
            if name not in by_name:
                by_name[name] = len(self.entities)
                self.entities.append(Entity(name, robot, kept))
            geom_entity[g] = by_name[name]
        self._geom_entity = geom_entity
        self._kept = np.array([e.kept for e in self.entities], dtype=bool)
        self._object_entity = {body: by_name[n[0]] for body, n in names.items()
                               if n[0].startswith("object:")}
        for robot, pairs in self._open.items():
            moved = {}
            for (a, b), rec in pairs.items():
                na, nb = by_name.get(old[a]), by_name.get(old[b])
                if na is not None and nb is not None:
                    moved[(na, nb)] = rec
            self._open[robot] = moved

    def hold(self, object_body: int, robot: str, held: bool) -> None:
        """An object is now held by ``robot``'s vacuum (its contacts are kept) or let go."""
        e = self._object_entity.get(object_body)
        if e is None:
            return
        self.entities[e].robot = robot if held else ""
        self.entities[e].kept = held
        self._kept[e] = held

    def collect(self, d: mj.Data, time: float) -> None:
        """Keep the robot contacts of the step just taken (at simulated ``time``, s)."""
        if d.ncon == 0:
            return
        geoms, dist = mj.contacts(d)
        ents = self._geom_entity[geoms]
        keep = (self._kept[ents[:, 0]] | self._kept[ents[:, 1]]) & (dist <= 0.0) \
            & (ents[:, 0] != ents[:, 1])
        if not keep.any():
            return
        for (a, b), depth in zip(ents[keep].tolist(), (-dist[keep]).tolist(), strict=True):
            pair = (a, b) if self.entities[a].name <= self.entities[b].name else (b, a)
            robots = {self.entities[a].robot, self.entities[b].robot} - {""}
            for robot in robots:
                rec = self._open.setdefault(robot, {}).get(pair)
                if rec is None:
                    self._open[robot][pair] = [time, time, depth, 1]
                else:  # (a pair of geoms may touch at several points in one step)
                    rec[3] += rec[1] != time
                    rec[1] = time
                    rec[2] = max(rec[2], depth)

    def take(self, robot: str) -> tuple[ContactPair, ...]:
        """The contacts of ``robot`` since its last report (and start a new report)."""
        pairs = self._open.pop(robot, {})
        out = tuple(ContactPair(self.entities[a].name, self.entities[b].name, rec[0], rec[1],
                                rec[2], int(rec[3]))
                    for (a, b), rec in sorted(pairs.items(), key=lambda kv: kv[1][0]))
        if out:
            self._history.setdefault(robot, deque(maxlen=HISTORY)).extend(out)
        return out

    def history(self, robot: str) -> tuple[ContactPair, ...]:
        """Every contact of ``robot`` reported so far (the latest :data:`HISTORY`), then the
        ones not reported yet."""
        pending = self._open.get(robot, {})
        now = tuple(ContactPair(self.entities[a].name, self.entities[b].name, rec[0], rec[1],
                                rec[2], int(rec[3])) for (a, b), rec in pending.items())
        return tuple(self._history.get(robot, ())) + now

    def forget(self, robot: str) -> None:
        """A robot left: drop its records."""
        self._open.pop(robot, None)
        self._history.pop(robot, None)


def _scenery_name(geom: str) -> str:
    """``scenery:<piece>`` of a world geom's name (``cell/table_top``, ``scenery/3/pillar``)."""
    if geom.startswith(CELL_PREFIX):
        return "scenery:" + geom[len(CELL_PREFIX):]
    if geom.startswith(BOX_PREFIX):
        return "scenery:" + geom[len(BOX_PREFIX):].split("/", 1)[-1]
    return "scenery:" + (geom or "world")
