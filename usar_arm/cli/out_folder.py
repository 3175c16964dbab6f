"""The folder a config command writes into (``tesseract-config --out``, ``moveit-config
--out``): checked before any work, and what else it holds reported after writing.

The rules: the folder is absent, empty, or a package usar-arm wrote before (its ``package.xml``
says so). Then the files the command writes replace theirs atomically, one by one
(:func:`usar_arm.core.fileio.write_tree_atomic`), and any other file in it is kept and listed:
it may be the user's, so usar-arm never deletes it. A path that is a file, lies under a file,
cannot be written, or names a folder holding other things is refused before anything is
discovered or written.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from usar_arm.core.errors import InvalidInputError

MARKER = "usar-arm"
"""What a ``package.xml`` usar-arm wrote says (its description and maintainer)."""


def _written_by_usar_arm(folder: Path) -> bool:
    try:
        return MARKER in (folder / "package.xml").read_text(errors="replace")
    except OSError:
        return False


def _listing(names: list[str], most: int = 5) -> str:
    shown = ", ".join(names[:most])
    return shown + (f" and {len(names) - most} more" if len(names) > most else "")


def check_out_folder(path: str | Path, option: str = "--out") -> Path:
    """The absolute folder ``path`` names, when a config may be written there.

    Raises:
        InvalidInputError: ``path`` is a file, lies under a file, cannot be written, or is a
            folder holding files of something other than a package usar-arm wrote.
    """
    folder = Path(path).expanduser().resolve()
    if folder.exists() and not folder.is_dir():
        raise InvalidInputError(f"{option} {path}: {folder} is a file, not a folder; give a "
                                "new folder (or one an earlier run of this command wrote)")
    ancestor = folder
    while not ancestor.exists():
        ancestor = ancestor.parent
        if ancestor.exists() and not ancestor.is_dir():
            raise InvalidInputError(f"{option} {path}: {ancestor} is a file, so no folder can "
                                    "be made under it; give a path under a folder")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise InvalidInputError(f"{option} {path}: cannot write into {ancestor} (permission "
                                "denied); give a folder you can write")
    if folder.is_dir():
        entries = sorted(p.name for p in folder.iterdir())
        if entries and not _written_by_usar_arm(folder):
            raise InvalidInputError(
                f"{option} {path}: {folder} already holds {_listing(entries)} and is not a "
                "package usar-arm wrote (its package.xml would say so); give a new or empty "
                "folder: usar-arm neither mixes its files into other folders nor deletes "
                "anything")
    return folder


def other_files(folder: Path, written: Iterable[str | Path]) -> list[str]:
    """Files under ``folder`` (relative paths, sorted) that are not among ``written`` (paths
    relative to ``folder`` or absolute)."""
    ours = {(folder / p).resolve() for p in written}
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*")
                  if p.is_file() and p.resolve() not in ours)


def report_other_files(folder: Path, others: list[str]) -> str:
    """The sentence saying which files were kept (empty when none)."""
    if not others:
        return ""
    return (f"{folder} also holds {len(others)} file(s) this command did not write, kept as "
            f"they were: {_listing(others)} (from an earlier, different config? usar-arm "
            "deletes nothing: remove them yourself if they are not needed)")
