"""Jobs whose workers fail on purpose, for the engine's tests (module-level functions: they
travel to worker processes by reference)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

Result = dict[str, np.ndarray]


def prepare(folder: str) -> str:
    """The context: a folder where the failures keep their marks."""
    return folder


def square(folder: str, chunk: np.ndarray) -> Result:
    """A healthy chunk: the squares of its numbers (and a little work)."""
    time.sleep(0.01)
    return {"values": chunk, "squares": chunk * chunk}


def slow_square(folder: str, chunk: np.ndarray) -> Result:
    """A healthy chunk of 0.2 s (Ray's start takes seconds: a helper gets some)."""
    time.sleep(0.2)
    return square(folder, chunk)


def _first_time(folder: str, name: str) -> bool:
    mark = Path(folder) / name
    try:
        fd = os.open(mark, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return False
    os.close(fd)
    return True


def dies_once_on_chunk_3(folder: str, chunk: np.ndarray) -> Result:
    """The worker process running the chunk holding 30 dies the first time (exit code 3)."""
    if 30 in chunk and _first_time(folder, "died"):
        os._exit(3)
    return square(folder, chunk)


def always_dies_on_chunk_3(folder: str, chunk: np.ndarray) -> Result:
    """The worker running the chunk holding 30 dies every time."""
    if 30 in chunk:
        os._exit(3)
    return square(folder, chunk)


def raises_once_on_chunk_3(folder: str, chunk: np.ndarray) -> Result:
    """The chunk holding 30 raises the first time."""
    if 30 in chunk and _first_time(folder, "raised"):
        raise ValueError("a passing fault in chunk 3")
    return square(folder, chunk)


def hangs_on_chunk_3(folder: str, chunk: np.ndarray) -> Result:
    """The chunk holding 30 never ends (a worker stuck in a library call)."""
    if 30 in chunk:
        time.sleep(3600)
    return square(folder, chunk)
