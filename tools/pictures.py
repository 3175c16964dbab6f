"""Every picture the README and the docs show, made by one command, each recording what made it.

A picture is an entry of :data:`PICTURES`: the PNG it writes (below the repository), the command
that makes it, and its inputs (files or globs: the code that draws it and the data it draws).
When a picture is written, a PNG text chunk (keyword ``usar-arm``) records that command and a
SHA-256 of its inputs; ``tests/test_pictures.py`` recomputes the hash in the default suite
(drawing nothing) and fails naming every picture whose inputs changed since it was drawn.

    python tools/pictures.py                # list the stale pictures (exit 1 when any is)
    python tools/pictures.py --write        # draw every picture again (make pictures)
    python tools/pictures.py --write NAME   # draw one (its name: the PNG's stem)
    python tools/pictures.py --stale        # draw the stale ones

A new picture (e.g. an RViz screenshot of the ROS node) is one more :func:`register` call, here
or in a module :data:`HOOKS` names: a function that writes the PNG at the path it is given,
with a scratch folder for what it needs on the way. Run them with the test venv's Python (they
run usar-arm; the viewer's screenshot needs Chromium, see ``tools/browser.py``).
"""

from __future__ import annotations

import argparse
import glob
import hashlib
import importlib
import json
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
KEYWORD = "usar-arm"
"""The keyword of the PNG text chunk that records what made a picture."""
KR60 = ("robots/generated/KR60.urdf", "robots/generated/KR60.srdf",
        "robots/generated/KR60.joint_limits.yaml")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True)
class Picture:
    """A picture the README or the docs show.

    Attributes:
        path: the PNG, relative to the repository. command: what makes it, as recorded.
        inputs: files or globs (relative to the repository) whose content it depends on.
        make: writes the PNG at the path it is given (a scratch folder second).
    """

    path: str
    command: str
    inputs: tuple[str, ...]
    make: Callable[[Path, Path], None]

    @property
    def name(self) -> str:
        """The PNG's stem: how ``--write NAME`` names it."""
        return Path(self.path).stem


PICTURES: dict[str, Picture] = {}
"""Every registered picture, by name."""
HOOKS: tuple[str, ...] = ("browser", "rviz_pictures")
"""Modules of ``tools/`` that register pictures of their own when imported."""


def register(picture: Picture) -> Picture:
    """Add ``picture`` to :data:`PICTURES` (a second picture of the same name is refused)."""
    if picture.name in PICTURES:
        raise ValueError(f"a picture named {picture.name} is registered already")
    PICTURES[picture.name] = picture
    return picture


# ------------------------------------------------------------------ the PNG text chunk


def _chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    if not data.startswith(PNG_SIGNATURE):
        raise ValueError("not a PNG file")
    out, at = [], len(PNG_SIGNATURE)
    while at < len(data):
        (length,) = struct.unpack(">I", data[at:at + 4])
        kind = data[at + 4:at + 8]
        out.append((kind, data[at + 8:at + 8 + length]))
        at += 12 + length
    return out


def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(
        ">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def read_record(path: Path) -> dict[str, str] | None:
    """What made the PNG at ``path`` (its ``usar-arm`` text chunk), None if it records nothing."""
    for kind, body in _chunks(path.read_bytes()):
        if kind == b"tEXt" and body.startswith(KEYWORD.encode() + b"\0"):
            return dict(json.loads(body[len(KEYWORD) + 1:].decode("latin-1")))
    return None


def write_record(path: Path, record: dict[str, str]) -> None:
    """Store ``record`` in the PNG at ``path`` (replacing an earlier one), before its end."""
    body = KEYWORD.encode() + b"\0" + json.dumps(record, sort_keys=True).encode("latin-1")
    kept = [(k, b) for k, b in _chunks(path.read_bytes())
            if not (k == b"tEXt" and b.startswith(KEYWORD.encode() + b"\0"))]
    out = PNG_SIGNATURE + b"".join(_chunk(k, b) for k, b in kept[:-1])
    path.write_bytes(out + _chunk(b"tEXt", body) + _chunk(*kept[-1]))


# ------------------------------------------------------------------ inputs and staleness


def input_files(picture: Picture, root: Path = ROOT) -> list[Path]:
    """The files a picture's inputs name, sorted (a pattern matching nothing is an error)."""
    files: set[Path] = set()
    for pattern in picture.inputs:
        found = [Path(p) for p in glob.glob(str(root / pattern), recursive=True)]
        if not found:
            raise FileNotFoundError(f"{picture.name}: input {pattern} matches no file")
        files |= {p for p in found if p.is_file()}
    return sorted(files)


def inputs_hash(picture: Picture, root: Path = ROOT) -> str:
    """SHA-256 of the picture's input files: each one's path (relative) and content."""
    digest = hashlib.sha256()
    for path in input_files(picture, root):
        digest.update(str(path.relative_to(root)).encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return f"sha256:{digest.hexdigest()}"


def staleness(picture: Picture, root: Path = ROOT) -> str | None:
    """Why ``picture`` must be drawn again (None when it is up to date)."""
    path = root / picture.path
    if not path.is_file():
        return "missing"
    record = read_record(path)
    if record is None:
        return "records nothing of what made it"
    if record.get("command") != picture.command:
        return f"made by another command ({record.get('command')!r})"
    if record.get("inputs") != inputs_hash(picture, root):
        return "its inputs changed since it was drawn"
    return None


def draw(picture: Picture, root: Path = ROOT) -> None:
    """Make the picture (in a scratch folder, then in place) and record what made it."""
    with tempfile.TemporaryDirectory(prefix=f"picture-{picture.name}-") as scratch:
        out = Path(scratch) / Path(picture.path).name
        picture.make(out, Path(scratch))
        write_record(out, {"command": picture.command, "inputs": inputs_hash(picture, root)})
        (root / picture.path).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(out, root / picture.path)


# ------------------------------------------------------------------ the pictures


def usar_arm(*argv: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """Run ``usar-arm ARGV`` with this Python in ``cwd`` (the repository's package first)."""
    done = subprocess.run([sys.executable, "-m", "usar_arm", *argv], cwd=cwd, text=True,
                          capture_output=True, check=False,
                          env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    if done.returncode != 0:
        raise RuntimeError(f"usar-arm {' '.join(argv)} failed ({done.returncode}):\n"
                           f"{done.stderr[-3000:]}")
    return done


def _made_by(argv: tuple[str, ...], produced: str) -> Callable[[Path, Path], None]:
    """A maker that runs ``usar-arm ARGV`` in the scratch folder (``{root}`` in an argument is
    the repository) and takes the PNG it writes there as ``produced``."""
    def make(out: Path, scratch: Path) -> None:
        usar_arm(*(a.replace("{root}", str(ROOT)) for a in argv), cwd=scratch)
        shutil.copyfile(scratch / produced, out)
    return make


REACH = ("reach", "--urdf", "{root}/robots/generated/KR60.urdf", "--scene", "table",
         "--resolution", "0.05", "--orientations", "64", "--out", "map")
register(Picture(
    "docs/images/reach-xz.png", "usar-arm " + " ".join(REACH) + "  (map/reach-xz.png)",
    (*KR60, "usar_arm/data/scenes/table.yaml", "usar_arm/cli/reach_cmd.py",
     "usar_arm/export/reach_plot.py", "usar_arm/workspace/reach*.py",
     "usar_arm/workspace/grid.py", "usar_arm/workspace/orientations.py",
     "usar_arm/workspace/solver.py", "usar_arm/workspace/kernels.py",
     "usar_arm/workspace/edge*.py", "usar_arm/workspace/query.py"),
    _made_by(REACH, "map/reach-xz.png")))

PLACE = ("place", "--urdf", "{root}/robots/generated/KR60.urdf", "--targets",
         "{root}/examples/workspace/table-targets.yaml", "--scene", "table", "--out", "cell")
register(Picture(
    "docs/images/placement.png", "usar-arm " + " ".join(PLACE) + "  (cell/placement.png)",
    (*KR60, "usar_arm/data/scenes/table.yaml", "examples/workspace/table-targets.yaml",
     "usar_arm/cli/place_cmd.py", "usar_arm/export/placement_plot.py",
     "usar_arm/workspace/placement.py", "usar_arm/workspace/targets.py",
     "usar_arm/workspace/solver.py", "usar_arm/workspace/kernels.py",
     "usar_arm/workspace/query.py"),
    _made_by(PLACE, "cell/placement.png")))


def _drive(out: Path, scratch: Path) -> None:
    # The run of docs/platform.md, section 3: its figures (bench/results/drive.json) come from
    # the same run as its picture; `python tools/figures.py --write` then updates the prose.
    done = usar_arm(*DRIVE, "--picture", str(out), "--json", cwd=scratch)
    (ROOT / "bench" / "results" / "drive.json").write_text(done.stdout)


DRIVE = ("drive", "--robot", "P3AT", "--start-position", "RobotStart2", "--waypoints", "7,-5",
         "10.25,-5", "10.25,0", "5.75,0", "5.75,-5", "7,-5", "-o", "square.bag", "--speed", "4")
register(Picture(
    "docs/images/drive.png",
    "usar-arm " + " ".join(DRIVE) + " --picture drive.png --json > bench/results/drive.json",
    ("usar_arm/cli/drive_cmd.py", "usar_arm/export/drive_plot.py", "usar_arm/export/world_plot.py",
     "usar_arm/control/drive_run.py", "usar_arm/control/pursuit.py", "usar_arm/control/skid.py",
     "usar_arm/sim/worlds/rooms.yaml", "usar_arm/sim/robots/p3at.yaml"),
    _drive))


def load_hooks() -> None:
    """Import the modules of :data:`HOOKS` (each registers its pictures)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    for module in HOOKS:
        importlib.import_module(module)


def main(argv: list[str] | None = None) -> int:
    load_hooks()
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--write", nargs="*", metavar="NAME", default=None,
                        help="draw these pictures again (none named: all)")
    parser.add_argument("--stale", action="store_true", help="draw the stale pictures again")
    args = parser.parse_args(argv)
    if args.write is not None or args.stale:
        unknown = sorted(set(args.write or ()) - set(PICTURES))
        if unknown:
            parser.error(f"no picture {', '.join(unknown)} (pictures: {', '.join(PICTURES)})")
        chosen = [PICTURES[n] for n in args.write] if args.write else [
            p for p in PICTURES.values() if not args.stale or staleness(p)]
        for picture in chosen:
            print(f"drawing {picture.path}: {picture.command}", file=sys.stderr)
            draw(picture)
        return 0
    stale = {p.path: why for p in PICTURES.values() if (why := staleness(p))}
    for path, why in stale.items():
        print(f"{path}: {why}")
    return 1 if stale else 0


if __name__ == "__main__":
    sys.modules.setdefault("pictures", sys.modules["__main__"])  # (the hooks register here)
    sys.exit(main())
