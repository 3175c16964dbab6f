"""A shipped name or a file: the one rule by which usar-arm tells them apart wherever a world or
a scene is named (``--world``, ``--scene``, ``Arm.plan(scene=...)``, a batch problem's
``scene``, the ROS node's scene).

* a :class:`~pathlib.Path`, or text with a folder separator (``/``, or the system's own) or a
  suffix (``.yaml``), is a **path**: that file, which must exist and be a file;
* a bare word is a **name**: a shipped world or scene of that name, whatever the working folder
  holds (a folder or file called ``default`` or ``table`` there does not hide the shipped one;
  ``./table`` names that file);
* a bare word that is no shipped name is the file of that name in the working folder when there
  is one (a file named without a suffix), else an error that names both tries.

Robots are never looked up as files: ``--robot KR60`` names a class on the server.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from usar_arm.core.errors import FileFormatError


@dataclass(frozen=True)
class Named:
    """What a given name or path stands for.

    Attributes:
        given: the text as given. shipped: the shipped name it stands for, or None.
        path: the file it stands for (None for a shipped name).
    """

    given: str
    shipped: str | None = None
    path: Path | None = None


def looks_like_path(text: str) -> bool:
    """Whether ``text`` is written as a path: it holds a folder separator or a suffix."""
    separators = {"/", os.sep} | ({os.altsep} if os.altsep else set())
    return any(s in text for s in separators) or Path(text).suffix != ""


def _file(text: str, kind: str, shipped: Sequence[str]) -> Path:
    path = Path(text)
    try:
        is_dir, exists = path.is_dir(), path.exists()
    except OSError as exc:  # e.g. a name longer than the file system allows
        raise FileFormatError(text, f"not a usable file name: {exc.strerror or exc}") from None
    names = ", ".join(shipped)
    if is_dir:
        raise FileFormatError(text, f"is a folder, not a {kind} file (a name without a folder "
                                    f"or suffix names a shipped {kind}: {names})")
    if not exists:
        raise FileFormatError(text, f"no such {kind} file (a name without a folder or suffix "
                                    f"names a shipped {kind}: {names})")
    return path


def resolve_name(given: str | os.PathLike[str], kind: str, shipped: Sequence[str]) -> Named:
    """The shipped ``kind`` (``"world"``, ``"scene"``) or the file that ``given`` stands for, by
    the rule of this module; ``shipped`` are the shipped names.

    Raises:
        FileFormatError: a path that is no file (missing, or a folder), or a bare word that is
            neither a shipped name nor a file here; the message says what was tried.
    """
    text = os.fspath(given)
    if not isinstance(given, str) or looks_like_path(text):
        return Named(text, path=_file(text, kind, shipped))
    if text in shipped:
        return Named(text, shipped=text)
    path = Path(text)
    if path.is_file():
        return Named(text, path=path)
    raise FileFormatError(text, f"no shipped {kind} of that name ({', '.join(shipped)}) and "
                                f"no such file{' (it is a folder)' if path.is_dir() else ''}")


def recorded(given: str | os.PathLike[str], kind: str, shipped: Sequence[str]) -> str:
    """What a file records for ``given`` so that it names the same from any folder: a shipped
    name as it is, a file by its absolute path (which the rule reads back as a path).

    Raises:
        FileFormatError: as :func:`resolve_name`.
    """
    named = resolve_name(given, kind, shipped)
    if named.shipped is not None:
        return named.shipped
    assert named.path is not None
    return str(named.path.resolve())
