"""The arm's vacuum gripper over the wire: close it and know whether it holds something, open
it, and watch it while a part is carried.

UDK's EFF line says only whether the vacuum is on (``{Status CLOSED}`` even with nothing under
it, ``Vacuum.uc``); the embedded simulator's GripTruth extension (``SEN {Type GripTruth}``)
says what it really holds. A grip is confirmed by GripTruth where the server sends it; on a
server that does not (a real UDK), :meth:`Vacuum.grip` answers None and the caller confirms by
the object's own pose (GetSTA: it rose with the arm).
"""

from __future__ import annotations

from collections.abc import Callable

from usar_arm.core.cell_errors import GripError
from usar_arm.core.errors import ResponseTimeoutError
from usar_arm.usarsim.client import UsarClient

GRIP_TRUTH_S = 1.0
"""Seconds to wait for a GripTruth after the EFF: a server without the extension sends none."""


class Vacuum:
    """A vacuum gripper of the robot on ``client`` (its effector name, ``KR60gripper``).

    Args:
        client: the robot's connection. name: the gripper's name. timeout: s to wait for
            the EFF that shows a command took effect (EFF lines come every 0.1 s).
    """

    def __init__(self, client: UsarClient, name: str, timeout: float = 3.0):
        self.client = client
        self.name = name
        self.timeout = timeout
        self.holding: str | None = None
        """What the vacuum holds, by the last confirmed grip (None: nothing, or unknown)."""
        self.has_truth = False
        """True once the server sent a GripTruth (the extension) for this vacuum."""

    def _now(self) -> float | None:
        eff = self.client.latest_eff(self.name)
        return None if eff is None else eff.time

    def grip(self, move: str) -> str | None:
        """``SET {Type Gripper} {Name n} {Opcode CLOSE}`` and wait for its EFF; returns the
        object held by GripTruth (None from a server without the extension).

        Raises:
            GripError: no CLOSED EFF, or GripTruth says nothing was gripped (the vacuum is
                opened again, so that it does not catch something later).
        """
        after = self._now()
        self.client.set_effector("Gripper", self.name, "CLOSE")
        try:
            eff = self.client.wait_effector(self.name, "CLOSED", after_time=after,
                                            timeout=self.timeout)
        except ResponseTimeoutError as exc:
            raise GripError(self.name, move, "an EFF with Status CLOSED", str(exc)) from None
        try:
            truth = self.client.wait_grip(self.name, after_time=eff.time,
                                          timeout=GRIP_TRUTH_S)
        except ResponseTimeoutError:
            self.holding = None
            return None
        self.has_truth = True
        if not truth.holding:
            self.client.set_effector("Gripper", self.name, "OPEN")
            raise GripError(self.name, move, "an object in its suction zone held",
                            "the simulator's GripTruth says it holds nothing (EFF says "
                            "CLOSED: UDK reports the vacuum on, not a grip)")
        self.holding = truth.object
        return truth.object

    def release(self, move: str) -> None:
        """``SET ... {Opcode OPEN}`` and wait for the EFF that shows it open.

        Raises:
            GripError: no OPEN EFF within the timeout.
        """
        after = self._now()
        self.client.set_effector("Gripper", self.name, "OPEN")
        try:
            self.client.wait_effector(self.name, "OPEN", after_time=after, timeout=self.timeout)
        except ResponseTimeoutError as exc:
            raise GripError(self.name, move, "an EFF with Status OPEN", str(exc)) from None
        self.holding = None

    def lost(self) -> str | None:
        """Why the held part is no longer held (the vacuum reports OPEN, or GripTruth holds
        nothing), or None while it is."""
        eff = self.client.latest_eff(self.name)
        if eff is not None and eff.status == "OPEN":
            return f"suction lost: {self.name} reports OPEN while carrying {self.holding}"
        truth = self.client.latest_grip(self.name)
        if self.has_truth and truth is not None and not truth.holding:
            return (f"suction lost: {self.name} holds nothing (GripTruth) while carrying "
                    f"{self.holding}")
        return None

    def monitor(self) -> Callable[[float], str | None]:
        """An :attr:`Executor.monitor <usar_arm.control.executor.Executor.monitor>` that
        stops the arm when the suction is lost mid-move."""
        return lambda _t: self.lost()
