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
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

from numba import njit

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
