"""The demo's pick-and-place, for real: the part and the bin created through the WorldController,
every move planned in the scene the simulator reports, the part gripped by the vacuum and
carried as an attached object, let go in the bin, and the result judged by the simulator.

:func:`run_pick_place` runs the moves of :func:`usar_arm.arm.cycle.pick_and_place`: after the
``grip`` move it closes the vacuum, confirms the grip (GripTruth, or GetSTA on a server without
the extension: the part must rise with the lift), reads where the part really is and attaches
it to the tool's centre point, so that every later plan checks it (the objects it rested on
may touch it until it is clear of them: :mod:`usar_arm.planning.carry_book`). While the part
is carried, the executor stops the arm if the suction is lost. After the ``release`` move it
opens the vacuum, detaches the part and plans the rest around where it fell.
:class:`Placement` is the judgement: the part's final pose by GetSTA against the place, and
every contact the simulator reported (its contact extension).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from usar_arm.arm.cell_session import CellSession
from usar_arm.arm.cycle import PLACE, CycleResult, Move, MoveResult
from usar_arm.arm.facade import Arm
from usar_arm.arm.vacuum import Vacuum
from usar_arm.control.executor import ExecutionOptions
from usar_arm.control.motion import MotionOptions
from usar_arm.core.cell_errors import GripError
from usar_arm.core.errors import UsarArmError
from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning.scene import Scene
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.contact_watch import ContactWatch

log = logging.getLogger("usar_arm.arm.pick_place")

PLACE_TOLERANCE_M = 0.005
"""How far (m, in x and y) the part may come to rest from the place and count as placed."""
FLOOR_TOLERANCE_M = 0.003
"""How far (m) the part's bottom may be from the bin's inner floor and count as resting on it."""
LIFT_MIN_M = 0.05
"""How far (m) the part must rise during the lift for a grip to count as taken."""


@dataclass(frozen=True)
class PickPlaceParts:
    """What the cycle handles, by name: the part, the bin, the vacuum, the link the part is
    attached to (the tool's centre point), the tool's links it may touch, and the robot (its
    INIT name, which names its contact reports)."""

    part: str = "part"
    bin: str = "bin"
    vacuum: str = "KR60gripper"
    tcp_link: str = "KR60gripper_tcp"
    touch_links: tuple[str, ...] = ("KR60gripper",)
    robot: str = "KR60"


@dataclass
class Placement:
    """The simulator's judgement of a pick-and-place.

    Attributes:
        gripped: the object the vacuum held (GripTruth, or the part when GetSTA saw it rise).
        final_pose: the part's resting pose (4x4, base_link) by GetSTA; None: it is gone.
        place_xy: where it was to be put (m). xy_error_m: how far from it it rests (m).
        floor_gap_m: its bottom above the bin's inner floor (m; negative: below it).
        arm_contacts: every contact of an arm link or the tool during the cycle.
        carried_contacts: the part's contacts while carried (between the grip and the
            release, but for those with what it rested on before the lift ended).
    """

    gripped: str | None = None
    final_pose: Array | None = None
    place_xy: tuple[float, float] = PLACE
    xy_error_m: float | None = None
    floor_gap_m: float | None = None
    arm_contacts: list[m.ContactPair] = field(default_factory=list)
    carried_contacts: list[m.ContactPair] = field(default_factory=list)
    contact_reports: int = 0

    @property
    def in_bin(self) -> bool:
        """The part rests on the bin's floor within the tolerances."""
        return (self.xy_error_m is not None and self.floor_gap_m is not None
                and self.xy_error_m <= PLACE_TOLERANCE_M
                and abs(self.floor_gap_m) <= FLOOR_TOLERANCE_M)

    @property
    def placed(self) -> bool:
        """In the bin, with no contact of the arm, the tool or the carried part."""
        return self.in_bin and not self.arm_contacts and not self.carried_contacts

    def line(self) -> str:
        """``part placed in the bin: yes|no (...)``, the demo's verdict line."""
        if self.final_pose is None:
            why = "GetSTA lists no part"
        else:
            assert self.xy_error_m is not None and self.floor_gap_m is not None
            why = (f"{self.xy_error_m * 1000:.1f} mm from the place in x, y, its bottom "
                   f"{self.floor_gap_m * 1000:+.1f} mm from the bin's floor; contacts: "
                   f"{len(self.arm_contacts)} of the arm and tool, "
                   f"{len(self.carried_contacts)} of the carried part; by the simulator")
        return f"part placed in the bin: {'yes' if self.placed else 'no'} ({why})"

    def as_json(self) -> dict[str, Any]:
        """The judgement for report.json (SI units)."""
        def pairs(found: list[m.ContactPair]) -> list[dict[str, Any]]:
            return [{"a": p.a, "b": p.b, "first_s": p.first, "last_s": p.last,
                     "depth_m": p.depth} for p in found]
        return {"placed": self.placed, "in_bin": self.in_bin, "gripped": self.gripped,
                "final_xyz_m": None if self.final_pose is None
                else self.final_pose[:3, 3].tolist(),
                "place_xy_m": list(self.place_xy), "xy_error_m": self.xy_error_m,
                "floor_gap_m": self.floor_gap_m, "tolerance_xy_m": PLACE_TOLERANCE_M,
                "arm_contacts": pairs(self.arm_contacts),
                "carried_contacts": pairs(self.carried_contacts),
                "contact_reports": self.contact_reports}


@dataclass
class PickPlaceResult:
    """The cycle's moves and the simulator's judgement; ``scenes``: the planner's scene at the
    grip (the part on the table) and at the end (the part in the bin)."""

    cycle: CycleResult
    placement: Placement
    scenes: dict[str, Scene] = field(default_factory=dict)
    carried_goals: list[Array] = field(default_factory=list)
    """The goals (joint values) of the moves made carrying the part."""
    carrying_chain: KinematicChain | None = None
    """The planner's arm while it carried the part (the part a link of it)."""


def _without(scene: Scene, name: str) -> Scene:
    """``scene`` without the object ``name`` (and its pieces ``name/...``)."""
    return Scene(scene.name, tuple(o for o in scene.objects
                                   if o.name != name and not o.name.startswith(name + "/")))


class _Run:
    """One pick-and-place: the state between the moves."""

    def __init__(self, arm: Arm, cell: CellSession, parts: PickPlaceParts):
        self.arm, self.cell, self.parts = arm, cell, parts
        client = arm.client
        assert client is not None, "run_pick_place needs a connected arm"
        self.vacuum = Vacuum(client, parts.vacuum)
        self.scene = cell.scene()
        self.carrying = False
        self.placement = Placement()
        self.grip_time = self.lift_end = self.release_time = 0.0
        self.rose_from: float | None = None
        self.scenes: dict[str, Scene] = {}
        self.carrying_chain: KinematicChain | None = None

    def grip(self, move: Move) -> None:
        """Close the vacuum, confirm what it holds, attach the part."""
        p = self.parts
        before = self.cell.pose(p.part)
        held = self.vacuum.grip(move.name)
        if held is not None and held != p.part:
            self.vacuum.release(move.name)
            raise GripError(p.vacuum, move.name, f"the {p.part} held", f"it holds {held}")
        self.grip_time = self.arm.asta_time()
        self.placement.gripped = held
        self.rose_from = None if before is None else float(before[:3, 3][2])
        self.scenes["grip"] = self.scene = self.cell.scene()
        q = self.arm.joints()
        self.arm.attach(p.part, link=p.tcp_link, scene=self.scene, touch_links=p.touch_links,
                        q=q)
        self.carrying_chain = self.arm.planning_robot.chain
        self.scene = _without(self.scene, p.part)
        self.carrying = True

    def lifted(self, move: Move) -> None:
        """After the lift: the part must have risen with the arm (GetSTA)."""
        p = self.parts
        self.lift_end = self.arm.asta_time()
        now = self.cell.pose(p.part)
        if self.rose_from is None or now is None or now[2, 3] < self.rose_from + LIFT_MIN_M:
            self.arm.detach(p.part, q=self.arm.joints())
            self.carrying = False
            raise GripError(p.vacuum, move.name, f"the {p.part} lifted with the tool",
                            "GetSTA shows it did not rise" if now is not None
                            else "GetSTA lists no part")
        if self.placement.gripped is None:
            self.placement.gripped = p.part

    def release(self, move: Move) -> None:
        """Open the vacuum, detach the part, and read the scene once it rests."""
        p = self.parts
        self.vacuum.release(move.name)
        self.release_time = self.arm.asta_time()
        self.arm.detach(p.part, q=self.arm.joints())
        self.carrying = False
        self.cell.resting(p.part)
        self.scene = self.cell.scene()

    def drop(self) -> None:
        """After a failure: nothing stays attached in the planner's world (the part is where
        the simulator has it, not in the gripper of the model)."""
        if self.carrying:
            self.carrying = False
            try:
                self.arm.detach(self.parts.part, q=self.arm.joints())
            except UsarArmError as exc:  # (the connection may be what failed)
                log.warning("could not detach %s after the failure: %s", self.parts.part, exc)

    def judge(self, watch: ContactWatch) -> Placement:
        """The part's final pose and the contacts, by the simulator."""
        p, out = self.parts, self.placement
        final = self.cell.resting(p.part)
        self.scenes["end"] = self.scene = self.cell.scene()
        out.final_pose = final
        if final is not None:
            out.xy_error_m = float(np.linalg.norm(final[:2, 3] - np.asarray(out.place_xy)))
            floor = self.scene.object(f"{p.bin}/floor")
            assert hasattr(floor.shape, "size"), "a bin's floor is a box"
            top = float(floor.pose[2, 3] + floor.shape.size[2] / 2)
            out.floor_gap_m = float(final[2, 3]) - self.half_height(final) - top
        pairs = watch.pairs()
        out.contact_reports = watch.reports
        robot = ("link:", "tool:")
        out.arm_contacts = [c for c in pairs if c.a.startswith(robot) or c.b.startswith(robot)]
        part = f"object:{p.part}"
        out.carried_contacts = [
            c for c in pairs if part in (c.a, c.b) and c not in out.arm_contacts
            and c.last >= self.grip_time and c.first <= self.release_time
            and not (c.first < self.lift_end and self._support(c))]
        return out

    def half_height(self, pose: Array) -> float:
        """Half the part's extent (m) along the world's z, from its class size."""
        cls = next(s for s in self.cell.cell.spawn if s.name == self.parts.part)
        size = np.asarray(cls.wc_class.size) * np.asarray(cls.scale)
        return float(np.abs(pose[2, :3]) @ size / 2)

    def _support(self, c: m.ContactPair) -> bool:
        """A contact of the part with the scenery or an object (what it rested on)."""
        other = c.b if c.a == f"object:{self.parts.part}" else c.a
        return other.startswith(("scenery:", "object:"))


def run_pick_place(arm: Arm, cell: CellSession, moves: list[Move],
                   motion: MotionOptions | None = None,
                   execution: ExecutionOptions | None = None, tip_correction: bool = False,
                   parts: PickPlaceParts | None = None,
                   progress: Callable[[int, MoveResult], None] | None = None
                   ) -> PickPlaceResult:
    """Run ``moves`` in the cell on the server, gripping and releasing where they say.

    Raises:
        GripError: the vacuum took nothing (or not the part) after the grip move, or the
            part did not rise with the lift (nothing stays attached).
        ExecutionAbortedError: as :meth:`Arm.execute`; also the suction lost while carrying.
        PlanningError: as :func:`usar_arm.control.motion.plan_motion`. Each error names the
            move in a note.
    """
    run = _Run(arm, cell, parts or PickPlaceParts())
    assert arm.client is not None, "run_pick_place needs a connected arm"
    result = CycleResult()
    carried: list[Array] = []
    after_grip = False
    with ContactWatch(arm.client.subscribe, run.parts.robot) as watch:
        for i, move in enumerate(moves):
            begin = time.perf_counter()
            executor = arm.executor(execution)
            try:
                plan = arm.plan(joints=move.joints, pose=move.pose, motion=move.motion,
                                scene=run.scene, options=motion)
                executor.monitor = run.vacuum.monitor() if run.carrying else None
                try:
                    report = arm.execute(plan.trajectory, goal_pose=move.pose,
                                         options=execution, tip_correction=tip_correction)
                finally:
                    executor.monitor = None
                if run.carrying:
                    carried.append(plan.goal)
                if after_grip:
                    run.lifted(move)
                    after_grip = False
                if move.then == "grip":
                    run.grip(move)
                    after_grip = True
                elif move.then == "release":
                    run.release(move)
            except Exception as exc:
                exc.add_note(f"during move {i + 1} ({move.name}, {move.motion.upper()})")
                run.drop()
                raise
            done = MoveResult(move, plan, report, time.perf_counter() - begin)
            result.moves.append(done)
            if progress is not None:
                progress(i, done)
        time.sleep(0.3)  # (the last contact report covers the end of the last move)
        placement = run.judge(watch)
    return PickPlaceResult(result, placement, run.scenes, carried, run.carrying_chain)
