"""Compiled kernels: the one module that imports ``numba``.

Every hot loop of the geometric core (batched forward kinematics, conservative bounding-volume
tests, the analytic IK) is a plain Python function over numpy arrays and scalars, decorated with
:func:`kernel`. The decorator compiles it with numba in *nopython* mode, caches the machine code on
disk next to the module (``__pycache__``), so a fresh process loads it instead of compiling it
again, and keeps IEEE semantics (no ``fastmath``): a kernel's answer must agree with its plain
numpy reference to the last bit that matters.

Kernels stay small, typed by their arguments (float64 arrays, int64 indices) and free of Python
objects, so the same function can be called uncompiled (``kernel.py_func``) as its own
reference in tests.

numba keys a cached kernel by its own module's file alone (modification time and size), but
kernels inline helpers from other modules (:mod:`.bounds` inlines :mod:`.bounds_scene`'s): a
checkout that pulls a change to a helper would go on loading machine code compiled from the
helper's old source. So on import the caches of the kernels' folders are dropped when the
kernel sources differ from those they were compiled from (:func:`drop_stale_caches`: a stamp
beside them holds the sources' hash); the next call compiles anew.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

from numba import njit

PACKAGE = Path(__file__).resolve().parents[1]
KERNEL_FOLDERS = (PACKAGE / "planning", PACKAGE / "workspace")
"""The folders whose modules define kernels (with :func:`kernel` or :func:`inline_kernel`)."""
STAMP = "kernel-sources.sha256"
"""The stamp's name, in the first folder's ``__pycache__``."""


def kernel_sources_digest(folders: tuple[Path, ...]) -> str:
    """SHA-256 over the names and texts of the modules in ``folders`` that import this one."""
    digest = hashlib.sha256()
    for folder in folders:
        for source in sorted(folder.glob("*.py")):
            text = source.read_bytes()
            if b"planning.jit import" in text:
                digest.update(source.name.encode() + b"\0" + text)
    return digest.hexdigest()


def drop_stale_caches(folders: tuple[Path, ...] = KERNEL_FOLDERS) -> bool:
    """Remove numba's cache files (``*.nbi``, ``*.nbc``) in the folders' ``__pycache__`` when
    the kernel sources' digest is not the stamp's, then stamp the digest; True when it did.
    A folder that cannot be written is left to numba (it caches elsewhere then)."""
    digest = kernel_sources_digest(folders)
    stamp = folders[0] / "__pycache__" / STAMP
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    try:
        for folder in folders:
            for cached in [*folder.glob("__pycache__/*.nbi"), *folder.glob("__pycache__/*.nbc")]:
                cached.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        partial = stamp.with_name(f"{STAMP}.{os.getpid()}")
        partial.write_text(digest)
        partial.replace(stamp)
    except OSError:
        return False
    return True


drop_stale_caches()

F = TypeVar("F", bound=Callable[..., Any])


def kernel(function: F) -> F:
    """Compile ``function`` with numba (nopython, cached on disk, no fastmath, GIL released)."""
    compiled = njit(cache=True, nogil=True, fastmath=False, error_model="numpy")(function)
    return cast(F, compiled)


def inline_kernel(function: F) -> F:
    """:func:`kernel` for a small helper that other kernels call in their inner loops: inlined
    into each caller (numba's IR-level inlining), so passing its array arguments costs nothing
    per call."""
    compiled = njit(cache=True, nogil=True, fastmath=False, error_model="numpy",
                    inline="always")(function)
    return cast(F, compiled)
