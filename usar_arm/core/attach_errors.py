"""The errors of carrying a body on the arm (:mod:`usar_arm.planning.attached`,
:mod:`usar_arm.planning.carry_book`, ``Robot.carrying`` and ``Arm.attach``): an object that
cannot be attached or detached (an unknown link, a name clash, nothing carried by that name),
and one in collision where it would be attached.

A branch of the error tree of :mod:`usar_arm.core.errors`: raised only by the attached-body
code of the planning layer; each carries its evidence as attributes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from usar_arm.core.errors import EXIT_IN_COLLISION, InvalidInputError, PlanningError, names_or_none


@dataclass(eq=False, repr=False)
class AttachError(InvalidInputError):
    """An object cannot be attached to (or detached from) the arm: an unknown link, a name
    that is already a link or a carried object, an object the scene lacks, nothing carried
    by that name.

    Attributes:
        body: the object's name. problem: what was wrong. known: the names that would have
            been accepted (links, objects, carried bodies).
    """

    body: str
    problem: str
    known: Sequence[str] = ()

    def message(self) -> str:
        """This error's text, from its evidence."""
        text = f"cannot attach '{self.body}': {self.problem}"
        if self.known:
            text += f" (known: {names_or_none(self.known)})"
        return text


@dataclass(eq=False, repr=False)
class AttachedCollisionError(PlanningError):
    """An object to attach is in collision, at the configuration it is attached at, with
    something other than its parent and touch links.

    Attributes:
        body: the object's name. contacts: (body, other, depth m) of each pair in contact.
    """

    exit_code = EXIT_IN_COLLISION
    body: str
    contacts: Sequence[tuple[str, str, float]]

    def message(self) -> str:
        """This error's text, from its evidence."""
        shown = ", ".join(f"{a}–{b} ({d * 1000:.1f} mm deep)" for a, b, d in self.contacts)
        return (f"'{self.body}' is in collision where it would be attached: {shown}; "
                "name the links it may touch (touch_links) or attach it elsewhere")
