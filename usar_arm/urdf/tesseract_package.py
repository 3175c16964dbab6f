"""The package name of a Tesseract config folder (docs/conventions.md section 6).

The folder's name is the ROS package name its SRDF's ``package://NAME/...`` URLs use, so it
must be a name ROS accepts. REP-144's mandatory rules: lowercase letters, digits and ``_``
separators only, starting with a letter, no two ``_`` in a row, at least two characters; as
``rosidl`` checks them, no trailing ``_`` either (``^[a-z]([a-z0-9_]?[a-z0-9]+)*$``).
"""

from __future__ import annotations

import re

from usar_arm.core.errors import InvalidInputError

_NAME = re.compile(r"[a-z]([a-z0-9_]?[a-z0-9]+)*")


def package_problem(name: str) -> str | None:
    """Which REP-144 rule ``name`` breaks (None when it is a valid package name)."""
    if len(name) < 2:
        return "it must have at least two characters"
    if name != name.lower():
        return "it must be lowercase"
    if not name[0].isascii() or not name[0].isalpha():
        return "it must start with a letter"
    bad = sorted({c for c in name if not (c.isascii() and (c.isalnum() or c == "_"))})
    if bad:
        return "it may hold only letters, digits and '_' (not " + \
            ", ".join(repr(c) for c in bad) + ")"
    if "__" in name or name.endswith("_"):
        return "'_' only separates words: not two in a row, not at the end"
    return None if _NAME.fullmatch(name) else "it does not follow REP-144"


def suggest_package_name(name: str, robot: str = "robot") -> str:
    """A valid package name close to ``name`` (``KR60-Tesseract`` -> ``kr60_tesseract``);
    ``<robot>_tesseract`` when nothing of ``name`` can be kept."""
    words = re.findall(r"[a-z0-9]+", name.lower())
    while words and not words[0][0].isalpha():
        words[0] = words[0].lstrip("0123456789")
        if not words[0]:
            words.pop(0)
    candidate = "_".join(words)
    if package_problem(candidate) is None:
        return candidate
    fallback = "_".join([*re.findall(r"[a-z0-9]+", robot.lower()), "tesseract"])
    return fallback if package_problem(fallback) is None else "robot_tesseract"


def check_package_name(name: str, robot: str = "robot") -> None:
    """Raise :class:`~usar_arm.core.errors.InvalidInputError` naming the broken rule and a valid
    name when the folder name ``name`` cannot be a ROS package name."""
    problem = package_problem(name)
    if problem is not None:
        raise InvalidInputError(
            f"the folder name '{name}' cannot be a ROS package name: {problem} (REP-144: "
            "lowercase letters, digits and '_', starting with a letter); the SRDF's "
            f"package:// URLs name the folder. Use e.g. '{suggest_package_name(name, robot)}'")
