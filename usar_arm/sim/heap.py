"""Giving freed heap pages back to the system after the physics model is rebuilt."""

from __future__ import annotations

import ctypes
import ctypes.util
from collections.abc import Callable


def _heap_trimmer() -> Callable[[int], int] | None:
    """glibc's ``malloc_trim`` (None elsewhere)."""
    name = ctypes.util.find_library("c")
    try:
        trim = getattr(ctypes.CDLL(name), "malloc_trim", None) if name else None
    except OSError:
        return None
    return trim if callable(trim) else None


_MALLOC_TRIM = _heap_trimmer()


def release_freed_memory() -> None:
    """Give the heap's free pages back to the system (glibc; elsewhere nothing).

    Every model rebuild frees and reallocates a few MiB; glibc keeps the freed pages and the
    heap fragments, so a server whose robots come and go grew by ~15 KiB per robot removed
    (17 MiB over 1,100 spawn/remove cycles, measured) while holding no more live memory.
    Trimming after a removal keeps it flat; it frees only what is free, so a real leak still
    shows in the soak test's memory slope.
    """
    if _MALLOC_TRIM is not None:
        _MALLOC_TRIM(0)
