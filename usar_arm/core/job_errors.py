"""The errors of workspace jobs (:mod:`usar_arm.workspace`): a map too large for the machine, a
placement target no base reaches, and running a job in chunks (process pool or Ray): a chunk
that failed twice, a cluster that cannot be used, finished chunks of another job.

A branch of the error tree of :mod:`usar_arm.core.errors`: the errors of the layer above the
arm's pipeline, raised only there; each carries its evidence as attributes.
"""

from __future__ import annotations

from collections.abc import Sequence

from usar_arm.core.errors import (
    EXIT_UNAVAILABLE,
    EXIT_WORKER_FAILED,
    IKError,
    InvalidInputError,
    UsarArmError,
)


class ChunkFailedError(UsarArmError):
    """A chunk of a distributed job failed twice (its worker died or raised); the chunks done
    so far are kept, and ``--resume`` continues from them."""

    exit_code = EXIT_WORKER_FAILED

    def __init__(self, chunk: int, attempts: int, reason: str):
        self.chunk = chunk
        self.attempts = attempts
        self.reason = reason
        super().__init__(f"chunk {chunk} failed {attempts} times ({reason}); the finished "
                         "chunks are kept: run again with --resume to continue")


class ClusterUnavailableError(UsarArmError):
    """The execution backend cannot be used: a Ray cluster that does not answer, or Ray not
    installed."""

    exit_code = EXIT_UNAVAILABLE

    def __init__(self, address: str, reason: str):
        self.address = address
        self.reason = reason
        super().__init__(f"cannot use the Ray cluster at '{address}': {reason}")


class ResumeMismatchError(InvalidInputError):
    """``--resume`` found finished chunks of another job in the output folder (another robot,
    scene, problems file or setting): they are not used, and nothing is computed.

    Attributes:
        folder: the folder of the chunks. found_key, key: the kept job's key and this job's.
        differences: what differs (e.g. ``problems``, ``settings``), empty when the kept job
            does not say.
    """

    def __init__(self, folder: str, found_key: str | None, key: str,
                 differences: Sequence[str] = ()):
        self.folder = folder
        self.found_key = found_key
        self.key = key
        self.differences = tuple(differences)
        what = (f"its {' and '.join(self.differences)} differ" if self.differences
                else "the robot, scene, input or settings differ")
        super().__init__(
            f"{folder} holds finished chunks of another job ({what}; kept key {found_key}, "
            f"this job's {key}): they would give another job's answers. Run without --resume "
            "to start over, or resume with the same input and settings")


class MapTooLargeError(InvalidInputError):
    """A reachability map would not fit in this machine's memory; nothing was computed."""

    def __init__(self, voxels: int, need_bytes: int, available_bytes: int,
                 resolution_that_fits_m: float):
        self.voxels = voxels
        self.need_bytes = need_bytes
        self.available_bytes = available_bytes
        self.resolution_that_fits_m = resolution_that_fits_m
        super().__init__(
            f"a map of {voxels:,} voxels needs about {need_bytes / 2**30:.1f} GiB, more than "
            f"half of the {available_bytes / 2**30:.1f} GiB available; use a resolution of at "
            f"least {resolution_that_fits_m:g} m (or restrict the map)")


class UnreachableTargetError(IKError):
    """A target pose of a placement study is reachable (collision-free) from no candidate
    base; the others may be."""

    def __init__(self, target: str, candidates: int, detail: str = ""):
        self.target = target
        self.candidates = candidates
        text = (f"target '{target}' is reachable collision-free from none of the {candidates} "
                f"candidate base poses")
        super().__init__(text + (f" ({detail})" if detail else ""))
