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
