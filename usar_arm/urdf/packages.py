"""Where a URDF's ``package://NAME/...`` and ``file://`` resources are, found the way ROS tools
find them: ``--package-path NAME=DIR`` first, then ``ROS_PACKAGE_PATH`` entries (a folder NAME
below one, or the entry itself when its name is NAME), ``AMENT_PREFIX_PATH`` prefixes
(``PREFIX/share/NAME``), and last the URDF's own ancestors holding a folder NAME (a package
checked out beside the description). Relative paths are relative to the URDF's folder."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import unquote, urlparse


@dataclass(frozen=True)
class PackagePaths:
    """How to resolve resources.

    Attributes:
        explicit: package name -> folder (``--package-path NAME=DIR``), searched first.
        environ: the environment to read ``ROS_PACKAGE_PATH`` and ``AMENT_PREFIX_PATH`` from
            (None: the process's).
    """

    explicit: Mapping[str, str] = field(default_factory=dict)
    environ: Mapping[str, str] | None = None

    def package_folders(self, name: str, urdf: Path | None) -> list[Path]:
        """Candidate folders of package ``name``, in search order (existing or not)."""
        env = os.environ if self.environ is None else self.environ
        out = [Path(self.explicit[name])] if name in self.explicit else []
        for entry in filter(None, env.get("ROS_PACKAGE_PATH", "").split(os.pathsep)):
            root = Path(entry)
            out += [root] if root.name == name else [root / name]
        for prefix in filter(None, env.get("AMENT_PREFIX_PATH", "").split(os.pathsep)):
            out.append(Path(prefix) / "share" / name)
        if urdf is not None:
            out += [parent / name for parent in urdf.resolve().parents]
        return out

    def resolve(self, uri: str, urdf: Path | None) -> tuple[Path | None, list[Path]]:
        """The file ``uri`` names (None when not found) and every place looked at."""
        parsed = urlparse(uri)
        if parsed.scheme == "package":
            rest = unquote(parsed.path).lstrip("/")
            tried = [folder / rest for folder in self.package_folders(parsed.netloc, urdf)]
        elif parsed.scheme == "file":
            tried = [Path(unquote(parsed.netloc + parsed.path))]
        else:
            path = Path(uri)
            base = urdf.parent if urdf is not None else Path.cwd()
            tried = [path if path.is_absolute() else base / path]
        return next((p for p in tried if p.is_file()), None), tried


def parse_package_option(text: str) -> tuple[str, str]:
    """``NAME=DIR`` -> (NAME, DIR) (ValueError naming the expected form)."""
    name, sep, folder = text.partition("=")
    if not sep or not name or not folder:
        raise ValueError(f"--package-path expects NAME=DIR, got '{text}'")
    return name, folder
