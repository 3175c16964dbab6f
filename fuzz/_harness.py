"""What the fuzz targets share: atheris set-up and a scratch file for loaders that read paths.

Each target is a script: ``python fuzz/fuzz_<name>.py [libFuzzer flags] [corpus dirs]``. A target
crashes (and libFuzzer saves the input as ``crash-<sha1>``) when the code under test raises
anything but the typed error its contract allows, or an invariant assertion fails.
"""

from __future__ import annotations

import atexit
import shutil
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import atheris

ROOT = Path(__file__).resolve().parents[1]


def scratch_file(name: str, with_meshes: bool = False) -> Path:
    """A file in a private temporary folder (removed at exit) that each input is written to.

    With ``with_meshes`` the folder holds a copy of the shipped scene meshes, so that the
    relative ``meshes/fixture.stl`` of the seed scenes loads.
    """
    folder = Path(tempfile.mkdtemp(prefix="usar-arm-fuzz-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    if with_meshes:
        shutil.copytree(ROOT / "usar_arm" / "data" / "scenes" / "meshes", folder / "meshes")
    return folder / name


def run(test_one_input: Callable[[bytes], None], dictionary: str) -> None:
    """Hand argv to libFuzzer and fuzz ``test_one_input`` until a crash or a limit.

    ``dictionary`` names the target's token list in ``fuzz/dicts``; it is used unless the
    command line gives its own ``-dict=``.
    """
    argv = list(sys.argv)
    if not any(a.startswith("-dict=") for a in argv):
        argv.insert(1, f"-dict={ROOT / 'fuzz' / 'dicts' / dictionary}")
    atheris.Setup(argv, test_one_input)
    atheris.Fuzz()
