"""Atomic file writing: a temporary file in the same folder, then a rename.

A reader (or a crash, even ``kill -9``) never sees a half-written file: each file is either its
old version (or absent, if it had none) or its complete new one.

Temporary files are hidden and named after their target and the writing process:
``.<name>.<pid>.<random>.tmp`` (folders too, for rosbag2 output). A process killed while
writing leaves its temporary behind; the next write of the same target removes every such
leftover whose process is gone (POSIX only; a process id that was reused keeps its leftover
until that process is gone too).
"""

from __future__ import annotations

import ctypes
import errno
import os
import re
import shutil
import stat
import tempfile
from collections.abc import Mapping
from pathlib import Path

_RENAME_EXCHANGE = 2  # linux/fs.h
_AT_FDCWD = -100


def _umask() -> int:
    """The process umask, read without changing it where the system allows (os.umask(0) would
    briefly give files created by other threads mode 0666)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _umask_mode() -> int:
    """0666 minus the process umask: what open() would have given a new file."""
    return (stat.S_IRUSR | stat.S_IWUSR | stat.S_IRGRP | stat.S_IWGRP | stat.S_IROTH
            | stat.S_IWOTH) & ~_umask()


def temporary_prefix(target: Path) -> str:
    """The name prefix of ``target``'s temporaries written by this process."""
    return f".{target.name}.{os.getpid()}."


def _leftover_pattern(target: Path) -> re.Pattern[str]:
    return re.compile(rf"\.{re.escape(target.name)}\.(\d+)\.[a-z0-9_]{{8}}\.tmp")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True  # (another thread of this process may be writing the same target)
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True
    return True


def remove_leftovers(target: str | Path) -> list[Path]:
    """Remove the temporaries of ``target`` left by processes that no longer run (files or
    folders named ``.<name>.<pid>.<random>.tmp`` beside it); returns what was removed."""
    target = Path(target)
    if os.name != "posix" or not target.parent.is_dir():
        return []
    pattern = _leftover_pattern(target)
    removed = []
    try:
        entries = list(os.scandir(target.parent))
    except OSError:
        return []
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None or _alive(int(match.group(1))):
            continue
        path = Path(entry.path)
        try:
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(path)
            else:
                path.unlink()
        except FileNotFoundError:
            continue  # (another writer removed it first)
        except OSError:
            continue
        removed.append(path)
    return removed


def _fsync_dir(folder: Path) -> None:
    """Make renames in ``folder`` durable (ignored where folders cannot be opened)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _stage(target: Path, content: str | bytes) -> str:
    """Write ``content`` to a new temporary beside ``target`` (flushed to disk); its path."""
    fd, tmp = tempfile.mkstemp(prefix=temporary_prefix(target), suffix=".tmp",
                               dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(content.encode() if isinstance(content, str) else content)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, _umask_mode())
    except BaseException:
        _unlink(tmp)
        raise
    return tmp


def _unlink(path: str) -> None:
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass


def write_atomic(path: str | Path, content: str | bytes) -> Path:
    """Write ``content`` to ``path`` atomically (creating parent folders)."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_leftovers(target)
    tmp = _stage(target, content)
    try:
        os.replace(tmp, target)
    except BaseException:
        _unlink(tmp)
        raise
    _fsync_dir(target.parent)
    return target


def write_tree_atomic(root: str | Path, files: Mapping[str, str | bytes]) -> list[Path]:
    """Write several files under ``root``: every temporary file first, then every rename, so a
    failure while writing leaves all the old files in place.

    Each file is atomic; the set is not (a kill between two renames leaves some files new and
    some old, each complete). The renames follow the mapping's order: put last the file whose
    presence should mean that the others are written.
    """
    base = Path(root)
    staged: list[tuple[str, Path]] = []
    try:
        for rel, content in files.items():
            target = base / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            remove_leftovers(target)
            staged.append((_stage(target, content), target))
    except BaseException:
        for tmp, _ in staged:
            _unlink(tmp)
        raise
    done = 0
    try:
        for tmp, target in staged:
            os.replace(tmp, target)
            done += 1
    except BaseException:
        for tmp, _ in staged[done:]:
            _unlink(tmp)
        raise
    for folder in {t.parent for _, t in staged}:
        _fsync_dir(folder)
    return [t for _, t in staged]


def exchange(a: str | Path, b: str | Path) -> bool:
    """Swap the paths ``a`` and ``b`` (files or folders, both existing) in one atomic step
    (Linux ``renameat2(RENAME_EXCHANGE)``); False where the system cannot, with nothing done."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    renameat2.restype = ctypes.c_int
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False  # (the file system or kernel does not support it)
    raise OSError(err, os.strerror(err), str(a), None, str(b))
