"""The arm's effectors on ROS, written once for both middlewares: the seed's usarsim_inf topics
and the gripper as a control_msgs GripperCommand action.

* ``<name>/status`` (usarsim_inf/EffectorStatus for a Gripper, ToolchangerStatus for a
  ToolChanger): one message per EFF line, ``frame_id`` the effector's name, OPEN=0/CLOSE=1,
  ToolType Gripper/Vacuum/ToolChanger -> 1/2/3 (else 0), tool_type and tool_name kept when the
  tool changer opens (the seed's RosSim). An EFF line of another type is dropped (logged once).
* ``<name>/command`` (usarsim_inf/EffectorCommand): OPEN sends ``SET {Type T} {Name n} {Opcode
  OPEN}``, anything else CLOSE. A gripper's command is gated as the seed gates it: while one is
  pending, later ones are ignored until a status line shows its state (added: or
  :data:`GATE_TIMEOUT_S` passed, so a lost SET cannot block the topic for good). When a tool
  changer goes CLOSE -> OPEN, the tool it held is forgotten (its commands ignored, its action's
  goals refused) until its EFF lines come back.
* ``<gripper>/gripper_cmd`` (GripperCommand, :class:`GripperAction`): see its docstring.
* with the node's ``gripper_joint_states``: per EFF line of a gripper, a JointState of its
  virtual joint ``<gripper>_suction`` alone on ``joint_states`` (what MoveIt's state monitor
  needs for the gripper controller of ``usar-arm moveit-config --gripper``).

Units: s; a gripper's position is its virtual joint ``<gripper>_suction`` (0 off, 1 on).
"""

from __future__ import annotations

import itertools
import logging
import math
import threading
import time
from dataclasses import dataclass

from usar_arm.core.errors import ResponseTimeoutError, UsarArmError
from usar_arm.ros.runner import Outcome
from usar_arm.ros.transport import (
    ActionKind,
    Counted,
    EffectorCommandRecord,
    EffectorStatusRecord,
    GoalHandle,
    GripperGoal,
    GripperRecord,
    JointStateRecord,
    Kind,
    Publisher,
    ToolchangerStatusRecord,
    Transport,
)
from usar_arm.urdf.discovery_file import discovery_document
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.inbox import Received

log = logging.getLogger("usar_arm.ros")

OPEN, CLOSE = 0, 1
"""usarsim_inf's states."""
GRIPPER, TOOL_CHANGER = "Gripper", "ToolChanger"
"""The EFF types the seed serves (compared case-sensitively, as RosSim does)."""
TOOL_TYPES = {"gripper": 1, "vacuum": 2, "toolchanger": 3}
"""usarsim_inf/ToolType of an EFF line's ToolType (any case; anything else 0, UNKNOWN)."""
SUCTION_SUFFIX = "_suction"
"""A vacuum gripper's virtual joint: ``<gripper>_suction``, 0 off (open), 1 on (closed)."""
CLOSE_ABOVE = 0.5
"""A GripperCommand position above this closes (switches the vacuum on); at or below opens."""
POSITION_SLACK = 1e-6
"""How far outside [0, 1] a goal's position may be and still be taken as 0 or 1."""
EFF_TIMEOUT_S = 2.0
"""How long a goal waits for the EFF status it asked for (s; EFF lines come every 0.1 s)."""
GRIP_TIMEOUT_S = 1.0
"""How long a goal waits for the GripTruth extension after that EFF (s; UDK sends none)."""
GATE_TIMEOUT_S = 2.0
"""How long a gripper command blocks later ones on the command topic at most (s)."""
INVALID = -1
"""The code a refused GripperCommand goal is finished with (the result has no field for it)."""


@dataclass(frozen=True)
class Effector:
    """An effector as the node serves it: ``name`` and EFF ``type`` (Gripper, ToolChanger)."""

    name: str
    type: str


def effectors_of(files: dict[str, str]) -> tuple[Effector, ...]:
    """The effectors a description's discovery record lists (``effectors``: name and type), a
    tool changer before its tools (others are served when their EFF lines name them)."""
    doc = discovery_document(files) or {}
    found = {e["name"]: Effector(str(e["name"]), str(e["type"]))
             for e in doc.get("effectors", []) if isinstance(e, dict) and "name" in e}
    return tuple(sorted(found.values(), key=lambda e: (e.type != TOOL_CHANGER, e.name)))


class EffectorTopics:
    """``<name>/status`` and ``<name>/command`` of every effector (the seed's usarsim_inf), from
    the connection's EFF lines (on its reader thread); ``joint_states``: where a gripper's
    virtual joint state goes (None: nowhere)."""

    def __init__(self, transport: Transport, client: UsarClient,
                 effectors: tuple[Effector, ...], counts: dict[str, int],
                 joint_states: Publisher | None = None):
        self.transport = transport
        self.client = client
        self.counts = counts
        self.joint_states = joint_states
        self._lock = threading.Lock()
        self._status: dict[str, Publisher] = {}
        self._types: dict[str, str] = {}
        self._tools: dict[str, tuple[int, str, int]] = {}  # changer -> (type, tool, state)
        self.detached: set[str] = set()
        self._gates: dict[str, tuple[int, float]] = {}  # gripper -> (state, monotonic)
        self._unknown: set[str] = set()
        for effector in effectors:
            self._serve(effector.name, effector.type)

    def _serve(self, name: str, type_: str) -> None:
        """Make ``name``'s topics (once)."""
        with self._lock:
            if name in self._status:
                return
            kind = Kind.TOOLCHANGER_STATUS if type_ == TOOL_CHANGER else Kind.EFFECTOR_STATUS
            topic = f"{name}/status"
            self._status[name] = Counted(self.transport.publisher(topic, kind, 2), topic,
                                         self.counts)
            self._types[name] = type_
        self.transport.subscribe(f"{name}/command", Kind.EFFECTOR_COMMAND,
                                 lambda record: self.command(name, record))

    def on_line(self, rec: Received) -> None:
        """The connection's subscriber: one status message per EFF line."""
        eff = rec.message
        if not isinstance(eff, m.Eff):
            return
        if eff.type not in (GRIPPER, TOOL_CHANGER):
            if eff.type not in self._unknown:
                self._unknown.add(eff.type)
                log.warning("Unknown effector type %s (EFF of %s): not served", eff.type,
                            eff.name)
            return
        self._serve(eff.name, eff.type)
        self.detached.discard(eff.name)  # its EFF lines are back: it is attached
        state = CLOSE if eff.status == "CLOSED" else OPEN
        stamp = self.transport.now()
        record: EffectorStatusRecord | ToolchangerStatusRecord
        if eff.type == TOOL_CHANGER:
            record = self._changer(eff, state, stamp)
        else:
            record = EffectorStatusRecord(stamp, eff.name, state)
            with self._lock:
                gate = self._gates.get(eff.name)
                if gate is not None and gate[0] == state:
                    del self._gates[eff.name]
        try:
            self._status[eff.name].publish(record)
            if self.joint_states is not None and eff.type == GRIPPER:
                self.joint_states.publish(JointStateRecord(
                    eff.time if self.transport.use_sim_time and eff.time is not None
                    else stamp, (f"{eff.name}{SUCTION_SUFFIX}",), (float(state),)))
        except Exception as exc:  # a publisher of a context shutting down: never kill the reader
            log.debug("not published: %s", exc)

    def _changer(self, eff: m.Eff, state: int, stamp: float) -> ToolchangerStatusRecord:
        previous = self._tools.get(eff.name)
        tool_type, tool = (previous[0], previous[1]) if previous else (0, "")
        if state == CLOSE:
            tool_type = TOOL_TYPES.get((eff.get("ToolType") or "").lower(), 0)
            tool = eff.get("Tool") or tool
        elif previous is not None and previous[2] == CLOSE and tool:
            self.detached.add(tool)  # CLOSE -> OPEN: the seed forgets the tool it dropped
            log.info("%s dropped %s: its command topic and action wait for its EFF lines",
                     eff.name, tool)
        self._tools[eff.name] = (tool_type, tool, state)
        return ToolchangerStatusRecord(stamp, eff.name, state, tool_type, tool)

    def command(self, name: str, record: EffectorCommandRecord) -> None:
        """``<name>/command``: SET OPEN or CLOSE (a gripper's gated, see the module)."""
        state = OPEN if record.state == OPEN else CLOSE
        type_ = self._types.get(name, GRIPPER)
        if name in self.detached:
            log.warning("%s/command ignored: %s is not attached", name, name)
            return
        if type_ == GRIPPER:
            now = time.monotonic()
            with self._lock:
                gate = self._gates.get(name)
                if gate is not None and now - gate[1] < GATE_TIMEOUT_S:
                    log.info("%s/command ignored: the command before it is still pending", name)
                    return
                self._gates[name] = (state, now)
        self.client.set_effector(type_, name, "OPEN" if state == OPEN else "CLOSE")


class GripperAction:
    """``<gripper>/gripper_cmd``, control_msgs GripperCommand, for a vacuum gripper as
    MoveIt's gripper_action_controller interface drives its virtual joint
    ``<gripper>_suction``:

    * ``command.position`` > :data:`CLOSE_ABOVE` switches the vacuum on (SET CLOSE), else off
      (SET OPEN); ``max_effort`` is not used. A position that is not finite or outside [0, 1]
      is refused (ROS 2: aborted; ROS 1: rejected), and so is a goal for a tool the tool
      changer dropped.
    * The goal succeeds when an EFF line shows the status asked for (``reached_goal``), within
      :data:`EFF_TIMEOUT_S`; else it is aborted. UDK's vacuum reports CLOSED even with nothing
      under it: ``stalled`` says whether it really holds an object, by the simulator's
      GripTruth extension (a parallel gripper stalls on the part it grips); on a server
      without it, ``stalled`` is False.
    * Feedback per EFF line while it waits; a newer goal pre-empts a waiting one; a cancel
      ends it CANCELED (the SET already sent stays sent).
    """

    def __init__(self, transport: Transport, client: UsarClient, gripper: str,
                 topics: EffectorTopics):
        self.client = client
        self.gripper = gripper
        self.topics = topics
        self._tickets = itertools.count(1)
        self.latest = 0
        transport.action(f"{gripper}/gripper_cmd", ActionKind.GRIPPER_COMMAND, self.arrived,
                         self.serve)

    def arrived(self, handle: GoalHandle) -> None:
        """Number the goal; it pre-empts any older one."""
        handle.ticket = self.latest = next(self._tickets)

    def serve(self, handle: GoalHandle) -> None:
        """Check the goal, SET the vacuum and wait for its EFF (and GripTruth) lines."""
        goal: GripperGoal = handle.goal
        problem = self._problem(goal)
        if problem:
            log.warning("gripper goal refused: %s", problem)
            handle.refuse(INVALID, problem)
            return
        handle.accept()
        want = "CLOSED" if goal.position > CLOSE_ABOVE else "OPEN"
        try:
            outcome = self._run(handle, want)
        except UsarArmError as exc:
            outcome = Outcome(False, INVALID, f"{self.gripper}: {exc}")
        log.info("gripper goal %s: %s", "succeeded" if outcome.succeeded else "ended",
                 outcome.message)
        try:
            handle.finish(outcome)
        except Exception as exc:  # Ctrl-C/SIGTERM shut the middleware down first
            log.debug("goal state not sent: %s", exc)

    def _problem(self, goal: GripperGoal) -> str:
        p = goal.position
        if not (math.isfinite(p) and math.isfinite(goal.max_effort)):
            return f"command.position {p} and max_effort {goal.max_effort} must be finite"
        if not -POSITION_SLACK <= p <= 1.0 + POSITION_SLACK:
            return (f"command.position {p} is outside [0, 1]: {self.gripper}{SUCTION_SUFFIX} "
                    "is 0 (vacuum off) or 1 (on)")
        if self.gripper in self.topics.detached:
            return f"{self.gripper} is not attached: its tool changer dropped it"
        return ""

    def _run(self, handle: GoalHandle, want: str) -> Outcome:
        before = self.client.latest_eff(self.gripper)
        after = before.time if before is not None else None
        self.client.set_effector(GRIPPER, self.gripper, "CLOSE" if want == "CLOSED" else "OPEN")
        deadline = time.monotonic() + EFF_TIMEOUT_S
        last: str | None = None
        while True:
            if handle.ticket != self.latest:
                return Outcome(False, INVALID, "pre-empted by a newer goal", preempted=True,
                               state=self._state(last, False, False))
            if handle.cancel_requested():
                return Outcome(False, INVALID, "cancelled", cancelled=True,
                               state=self._state(last, False, False))
            if time.monotonic() > deadline:
                return Outcome(False, INVALID, f"no EFF of {self.gripper} with Status {want} "
                               f"within {EFF_TIMEOUT_S:g} s (last: {last})",
                               state=self._state(last, False, False))
            try:
                eff = self.client.wait_effector(self.gripper, after_time=after, timeout=0.1)
            except ResponseTimeoutError:
                continue
            after, last = eff.time, eff.status
            if eff.status == want:
                break
            handle.feedback(self._state(last, False, False))
        held = self._held(eff.time)
        state = self._state(last, held is not None, True)
        handle.feedback(state)
        what = f"holds {held}" if held else "holds nothing"
        return Outcome(True, 0, f"{self.gripper} {want}, {what}", state=state)

    def _held(self, after: float | None) -> str | None:
        """The object the vacuum holds by its next GripTruth line (None: nothing, or no
        extension on this server)."""
        try:
            grip = self.client.wait_grip(self.gripper, after_time=after, timeout=GRIP_TIMEOUT_S)
        except ResponseTimeoutError:
            return None
        return (grip.object or "an object") if grip.holding else None

    @staticmethod
    def _state(status: str | None, stalled: bool, reached: bool) -> GripperRecord:
        return GripperRecord(1.0 if status == "CLOSED" else 0.0, 0.0, stalled, reached)


def serve_effectors(transport: Transport, client: UsarClient, files: dict[str, str],
                    counts: dict[str, int], joint_states: Publisher | None = None
                    ) -> tuple[EffectorTopics, list[GripperAction]]:
    """Serve the effectors of a description (its discovery record's ``effectors``): the
    topics, and one GripperCommand action per gripper (``joint_states``: see
    :class:`EffectorTopics`). The caller subscribes ``topics.on_line`` to the connection."""
    effectors = effectors_of(files)
    topics = EffectorTopics(transport, client, effectors, counts, joint_states)
    actions = [GripperAction(transport, client, e.name, topics)
               for e in effectors if e.type == GRIPPER]
    return topics, actions
