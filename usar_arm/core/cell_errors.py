"""The errors of a physical cell (:mod:`usar_arm.usarsim.world_controller`, the pick and place
of :mod:`usar_arm.arm.pick_place`): a WorldController command that was not carried out, a grip
that did not take or let go, a part that is not where it was put.

A branch of the error tree of :mod:`usar_arm.core.errors`: what only a cell with simulated
objects can fail at, judged by what the server reports (GetSTA, the vacuum's status); each
carries its evidence as attributes.
"""

from __future__ import annotations

from dataclasses import dataclass

from usar_arm.core.errors import EXIT_UNAVAILABLE, UsarArmError, aside


@dataclass(eq=False, repr=False)
class WorldControllerError(UsarArmError):
    """A CONTROL command was not carried out (UDK answers none of them; the client finds out
    from GetSTA): the command, what was expected, and what GetSTA showed instead."""

    exit_code = EXIT_UNAVAILABLE
    command: str
    expected: str
    seen: str
    hint: str = ""

    def message(self) -> str:
        """This error's text, from its evidence."""
        return (f"`{self.command}` was not carried out: expected {self.expected}, GetSTA "
                f"shows {self.seen}" + aside(self.hint))


@dataclass(eq=False, repr=False)
class GripError(UsarArmError):
    """A vacuum did not take (or let go of) what a move asked of it: the vacuum, the move, what
    was expected and what the server said instead. Nothing is attached in the planner's world
    when a grip fails."""

    exit_code = EXIT_UNAVAILABLE
    vacuum: str
    move: str
    expected: str
    seen: str

    def message(self) -> str:
        """This error's text, from its evidence."""
        return f"{self.vacuum} after move '{self.move}': expected {self.expected}, but {self.seen}"


class PlacementError(UsarArmError):
    """The carried part is not where the cycle put it, by the simulator's GetSTA."""

    exit_code = EXIT_UNAVAILABLE
