"""Failures of a physical cell: a WorldController that did not do what it was asked."""

from __future__ import annotations

from usar_arm.core.errors import EXIT_UNAVAILABLE, UsarArmError


class WorldControllerError(UsarArmError):
    """A CONTROL command was not carried out (UDK answers none of them; the client finds out
    from GetSTA): the command, what was expected, and what GetSTA showed instead."""

    exit_code = EXIT_UNAVAILABLE

    def __init__(self, command: str, expected: str, seen: str, hint: str = ""):
        self.command = command
        self.expected = expected
        self.seen = seen
        self.hint = hint
        text = f"`{command}` was not carried out: expected {expected}, GetSTA shows {seen}"
        super().__init__(text + (f" ({hint})" if hint else ""))


class GripError(UsarArmError):
    """A vacuum did not take (or let go of) what a move asked of it: the vacuum, the move, what
    was expected and what the server said instead. Nothing is attached in the planner's world
    when a grip fails."""

    exit_code = EXIT_UNAVAILABLE

    def __init__(self, vacuum: str, move: str, expected: str, seen: str):
        self.vacuum = vacuum
        self.move = move
        self.expected = expected
        self.seen = seen
        super().__init__(f"{vacuum} after move '{move}': expected {expected}, but {seen}")


class PlacementError(UsarArmError):
    """The carried part is not where the cycle put it, by the simulator's GetSTA."""

    exit_code = EXIT_UNAVAILABLE
