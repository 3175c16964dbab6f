#!/usr/bin/env python3
"""Create one isolated virtual environment per benchmark peer (stdlib only).

    python3 bench/peers/venvs.py                   # all peers
    python3 bench/peers/venvs.py --only mplib,toppra
    python3 bench/peers/venvs.py --python mplib    # print that venv's python path
    python3 bench/peers/venvs.py --list            # peers and their pins

Venvs live in bench/.venvs/<peer> (git-ignored).  A venv whose marker file
(.installed, holding the pins it was built with) matches is skipped, so the
script is idempotent; a venv whose pins changed is rebuilt.  Exits non-zero
naming the peer whose install failed.

VAMP (KavrakiLab/vamp) is a peer that this script does not install: its pip
package downloads its C++ dependencies while it builds, so offline it is built
from its sources by hand (see bench/README-peers.md) into a venv of its own,
found where :func:`external_venv` looks (USAR_ARM_VAMP_VENV, else a link
bench/.venvs/vamp, else the default build folder); the stage skips it, saying
how to build it, when none holds an importable ``vamp``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

VENV_ROOT = Path(__file__).resolve().parents[1] / ".venvs"

# peer -> pip requirements (pinned).  numpy<2 for mplib: 0.2.1 crashes with numpy 2.
PEERS: dict[str, list[str]] = {
    "mplib": ["mplib==0.2.1", "numpy<2"],
    "roboplan": ["roboplan==0.7.0"],
    "pytracik": ["pytracik==0.0.3"],
    "opw": ["py-opw-kinematics==1.3.0"],
    "ikpy": ["ikpy==4.2.1"],
    "toppra": ["toppra==0.6.10"],
    # ROS-Industrial's planning stack (OMPL, TrajOpt, OPW/KDL, Bullet/FCL): the consumer tests'
    # instrument (tests/consumers; pyyaml: it reads the scene files itself) as well as a
    # benchmark peer; never a dependency of usar-arm.
    "tesseract": ["tesseract-robotics==0.5.1", "pyyaml==6.0.3"],
}
MARKER = ".installed"
EXTERNAL: dict[str, dict[str, str]] = {
    "vamp": {
        "env": "USAR_ARM_VAMP_VENV",
        "default": "/work/vamp-work/venv",
        "package": "vamp",
        "built": "KavrakiLab/vamp f6de6a7 (vamp-planner 0.6.4), built from source",
        "how": "build VAMP from its sources into a venv (its pip package fetches its C++ "
               "dependencies at build time; recipe in bench/README-peers.md) and set "
               "USAR_ARM_VAMP_VENV to it or link it as bench/.venvs/vamp",
    },
}
"""Peers built by hand, not by this script: where their venv is looked for (the variable,
then ``bench/.venvs/<peer>``, then ``default``), the package that must import, what was built,
and how to build it."""


def external_venv(peer: str) -> Path:
    """The venv of a hand-built peer (:data:`EXTERNAL`): ``$<env>`` when set, else
    ``bench/.venvs/<peer>`` when it exists (a link to the build's venv), else the default."""
    e = EXTERNAL[peer]
    if os.environ.get(e["env"]):
        return Path(os.environ[e["env"]])
    if venv_dir(peer).exists():
        return venv_dir(peer)
    return Path(e["default"])


def venv_dir(peer: str) -> Path:
    return VENV_ROOT / peer


def python_path(peer: str) -> Path:
    """Path of the python executable of a peer's venv (may not exist yet)."""
    if peer not in PEERS and peer not in EXTERNAL:
        raise KeyError(f"unknown peer {peer!r}; known: {', '.join([*PEERS, *EXTERNAL])}")
    sub = "Scripts/python.exe" if os.name == "nt" else "bin/python"
    return (external_venv(peer) if peer in EXTERNAL else venv_dir(peer)) / sub


def is_ready(peer: str) -> bool:
    """True when the peer's venv is built: its marker holds the current pins, or (a
    hand-built peer) its package's ``__init__.py`` is in the venv's site-packages."""
    if peer in EXTERNAL:
        lib = external_venv(peer) / "lib"
        package = EXTERNAL[peer]["package"]
        return python_path(peer).is_file() and any(
            lib.glob(f"python3*/site-packages/{package}/__init__.py"))
    marker = venv_dir(peer) / MARKER
    return marker.is_file() and marker.read_text().split() == PEERS[peer]


def missing_reason(peer: str) -> str:
    """Why a peer's venv is not ready, and how to make it (one line)."""
    if peer in EXTERNAL:
        return (f"no {EXTERNAL[peer]['package']} in {external_venv(peer)}: "
                f"{EXTERNAL[peer]['how']}")
    return (f"no venv at {venv_dir(peer)} (create it with "
            f"`python3 bench/peers/venvs.py --only {peer}`)")


def _log(msg: str) -> None:
    print(f"[venvs] {msg}", file=sys.stderr, flush=True)


def create(peer: str, force: bool = False) -> None:
    """Create the venv of one peer; raise RuntimeError if pip fails."""
    d = venv_dir(peer)
    if is_ready(peer) and not force:
        _log(f"{peer}: ready ({d}), skipped")
        return
    if d.exists():
        _log(f"{peer}: removing stale {d}")
        shutil.rmtree(d)
    _log(f"{peer}: creating venv {d}")
    venv.EnvBuilder(with_pip=True, clear=True).create(d)
    py = str(python_path(peer))
    for cmd in (
        [py, "-m", "pip", "install", "--quiet", "--upgrade", "pip"],
        [py, "-m", "pip", "install", "--quiet", *PEERS[peer]],
    ):
        _log(f"{peer}: {' '.join(cmd[1:])}")
        r = subprocess.run(cmd, stdout=sys.stderr, stderr=sys.stderr)
        if r.returncode != 0:
            raise RuntimeError(f"{peer}: '{' '.join(cmd[3:])}' exited {r.returncode}")
    (d / MARKER).write_text(" ".join(PEERS[peer]) + "\n")
    _log(f"{peer}: installed {' '.join(PEERS[peer])}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--only", help="comma-separated peers to create (default: all)")
    ap.add_argument("--force", action="store_true", help="rebuild even if the marker exists")
    ap.add_argument(
        "--python", metavar="PEER", help="print the python executable of PEER's venv and exit"
    )
    ap.add_argument(
        "--list", action="store_true", help="print peers, pins and readiness, then exit"
    )
    a = ap.parse_args(argv)
    if a.python:
        try:
            print(python_path(a.python))
        except KeyError as e:
            print(e.args[0], file=sys.stderr)
            return 2
        return 0 if is_ready(a.python) else 1
    if a.list:
        for p, reqs in PEERS.items():
            print(f"{p}\t{' '.join(reqs)}\t{'ready' if is_ready(p) else 'missing'}")
        for p, e in EXTERNAL.items():
            print(f"{p}\t{e['built']} (by hand, {external_venv(p)})\t"
                  f"{'ready' if is_ready(p) else 'missing'}")
        return 0
    peers = [p.strip() for p in a.only.split(",") if p.strip()] if a.only else list(PEERS)
    hand = [p for p in peers if p in EXTERNAL]
    for p in hand:
        _log(f"{p}: not installed by this script: "
             + ("ready" if is_ready(p) else missing_reason(p)))
    peers = [p for p in peers if p not in EXTERNAL]
    unknown = [p for p in peers if p not in PEERS]
    if unknown:
        print(f"unknown peer(s): {', '.join(unknown)}; known: {', '.join(PEERS)}", file=sys.stderr)
        return 2
    failed = []
    for p in peers:
        try:
            create(p, force=a.force)
        except Exception as e:
            _log(f"FAILED {e}")
            failed.append(p)
    if failed:
        print(f"failed to install: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
