"""Problems of a batch job, one JSON object per line (JSON Lines).

``{"id": "a", "ik": {"pose": [1.2, 0, 1.0, 3.14159, 0, 0], "seed": [0, -1, 1, 0, 0.5, 0]}}``
``{"id": "b", "ik": {"pose": <4x4 rows>, "all": true}, "scene": "table"}``
``{"id": "c", "plan": {"start": [...6], "goal": [...6]}, "scene": "table"}``
``{"id": "d", "plan": {"start": [...6], "pose": [1.4, -0.4, 1.0, 3.14, 0, 0], "motion": "lin"}}``
``{"id": "e", "plan": {...}, "scene": "table", "attach": {"name": "part", "link": "KR60gripper_tcp",
"touch_links": ["KR60gripper"]}}``

Poses are tool0 in base_link: X Y Z (m) and roll, pitch, yaw (rad, fixed axes), or a 4x4
matrix. ``scene`` (optional) names a shipped scene or a scene file. ``attach`` (optional) is
one object or a list of objects the arm carries (:mod:`usar_arm.planning.attach_file`'s
format): a new body with its shape and grasp (``xyz``/``rpy`` in the link frame), or a scene
object's name, grasped where it stands at the plan's start (an IK problem's seed). ``id`` is any
JSON value,
copied to the result. Blank lines and lines starting with ``#`` are skipped. A line that is not
a valid problem becomes a :class:`BadLine` (its result says why); the others still run.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.core.errors import FileFormatError
from usar_arm.core.inputs import rigid_defects
from usar_arm.core.spatial import Array, rpy_to_matrix, transform
from usar_arm.planning.attach_file import AttachRequest, parse_attach
from usar_arm.planning.attached import shape_key

KINDS = ("ik", "plan")
MOTIONS = ("ptp", "lin")


@dataclass(frozen=True)
class Problem:
    """One problem (every array in SI units; joints in the arm's order).

    Attributes:
        line: its 1-based line in the file. id: the line's ``id`` (any JSON value) or None.
        kind: ``ik`` or ``plan``. scene: a scene name or file, or None (no obstacles).
        pose: 4x4 goal of tool0 (ik; plan to a pose). seed: joints to stay near (ik).
        all: every IK solution (ik). start, goal: joints (plan). motion: ``ptp`` or ``lin``.
        attach: the objects the arm carries.
    """

    line: int
    id: Any
    kind: str
    scene: str | None = None
    pose: Array | None = None
    seed: Array | None = None
    all: bool = False
    start: Array | None = None
    goal: Array | None = None
    motion: str = "ptp"
    attach: tuple[AttachRequest, ...] = ()

    def content(self) -> list[Any]:
        """Everything the problem's answer depends on, as JSON values (arrays as nested
        lists of floats, exact): for a job's key."""
        return [self.line, self.id, self.kind, self.scene, _listed(self.pose),
                _listed(self.seed), self.all, _listed(self.start), _listed(self.goal),
                self.motion, [[a.name, a.link, list(a.touch_links),
                               None if a.shape is None else repr(shape_key(a.shape)),
                               _listed(a.pose)] for a in self.attach]]


def _listed(a: Array | None) -> list[Any] | None:
    return None if a is None else np.asarray(a, float).tolist()


@dataclass(frozen=True)
class BadLine:
    """A line that is not a valid problem, and why."""

    line: int
    id: Any
    message: str


class _Bad(Exception):
    pass


def _vector(value: Any, what: str) -> Array:
    if not isinstance(value, list) or not value or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise _Bad(f"{what} must be a list of numbers, got {json.dumps(value)[:80]}")
    out = np.asarray(value, float)
    if not np.all(np.isfinite(out)):
        raise _Bad(f"{what} has a non-finite number")
    return out


def _pose(value: Any, what: str) -> Array:
    if isinstance(value, list) and len(value) == 4 and all(isinstance(r, list) for r in value):
        rows = [_vector(r, what) for r in value]
        if any(len(r) != 4 for r in rows):
            raise _Bad(f"{what} as a matrix must be 4x4")
        t = np.array(rows)
        off, det, row = rigid_defects(t)
        if off > 1e-6 or det < 0 or row > 1e-9:
            raise _Bad(f"{what} is not a rigid transform (orthonormal rotation, det +1, "
                       "bottom row 0 0 0 1)")
        return t
    v = _vector(value, what)
    if len(v) != 6:
        raise _Bad(f"{what} needs 6 numbers (X Y Z m, roll pitch yaw rad) or a 4x4 matrix, "
                   f"got {len(v)}")
    return transform(rpy_to_matrix(v[3:]), v[:3])


def _attach(value: Any, base: Path) -> tuple[AttachRequest, ...]:
    entries = value if isinstance(value, list) else [value]
    try:
        out = tuple(parse_attach(e, "attach", base, f"attach[{i}]" if isinstance(value, list)
                                 else "attach") for i, e in enumerate(entries))
    except FileFormatError as exc:
        raise _Bad(str(exc)) from None
    return out


def _problem(line: int, doc: Any, base: Path) -> Problem:
    if not isinstance(doc, dict):
        raise _Bad("a problem is a JSON object with 'ik' or 'plan'")
    kinds = [k for k in KINDS if k in doc]
    if len(kinds) != 1:
        raise _Bad(f"a problem has exactly one of 'ik' or 'plan', got {sorted(doc)}")
    unknown = sorted(set(doc) - {"id", "scene", "attach", *KINDS})
    if unknown:
        raise _Bad(f"unknown key {unknown[0]!r} (expected id, scene, attach, ik or plan)")
    attach = _attach(doc.get("attach", []), base)
    scene = doc.get("scene")
    if scene is not None and (not isinstance(scene, str) or not scene):
        raise _Bad("'scene' names a shipped scene or a scene file")
    kind = kinds[0]
    body = doc[kind]
    if not isinstance(body, dict):
        raise _Bad(f"'{kind}' must be an object")
    if kind == "ik":
        extra = sorted(set(body) - {"pose", "seed", "all"})
        if extra or "pose" not in body:
            raise _Bad(f"'ik' takes pose (required), seed, all; got {sorted(body)}")
        if not isinstance(body.get("all", False), bool):
            raise _Bad("'all' is true or false")
        seed = _vector(body["seed"], "ik.seed") if "seed" in body else None
        if seed is None and any(a.shape is None for a in attach):
            raise _Bad("an IK problem grasps a scene object at its 'seed': give one")
        return Problem(line, doc.get("id"), kind, scene, _pose(body["pose"], "ik.pose"), seed,
                       bool(body.get("all", False)), attach=attach)
    extra = sorted(set(body) - {"start", "goal", "pose", "motion"})
    if extra or "start" not in body or (("goal" in body) == ("pose" in body)):
        raise _Bad(f"'plan' takes start and exactly one of goal (joints) or pose; got "
                   f"{sorted(body)}")
    motion = body.get("motion", "ptp")
    if motion not in MOTIONS:
        raise _Bad(f"plan.motion is ptp or lin, got {motion!r}")
    return Problem(line, doc.get("id"), kind, scene, _pose(body["pose"], "plan.pose")
                   if "pose" in body else None, None, False,
                   _vector(body["start"], "plan.start"),
                   _vector(body["goal"], "plan.goal") if "goal" in body else None, motion,
                   attach)


def parse_problems(text: str, base: Path = Path(".")) -> tuple[list[Problem], list[BadLine]]:
    """The problems of a JSON Lines text and the lines that are not problems (``base``: the
    folder attached bodies' mesh files are relative to)."""
    good: list[Problem] = []
    bad: list[BadLine] = []
    for n, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if not stripped or stripped.startswith("#"):
            continue
        try:
            doc = json.loads(stripped, parse_constant=lambda c: math.nan)
        except json.JSONDecodeError as exc:
            bad.append(BadLine(n, None, f"not JSON: {exc.msg} at column {exc.colno}"))
            continue
        try:
            good.append(_problem(n, doc, base))
        except _Bad as exc:
            bad.append(BadLine(n, doc.get("id") if isinstance(doc, dict) else None, str(exc)))
    return good, bad


def read_problems(path: str | Path) -> tuple[list[Problem], list[BadLine]]:
    """:func:`parse_problems` of a file.

    Raises:
        FileFormatError: the file cannot be read, is not UTF-8 or holds no line at all.
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise FileFormatError(str(path), f"cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise FileFormatError(str(path), f"not UTF-8 text (offset {exc.start})") from None
    good, bad = parse_problems(text, Path(path).parent)
    if not good and not bad:
        raise FileFormatError(str(path), "no problems (expected one JSON object per line)")
    return good, bad
