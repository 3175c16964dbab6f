"""The errors of workspace jobs (:mod:`usar_arm.workspace`): a map too large for the machine, a
placement target no base reaches, and running a job in chunks (process pool or Ray): a chunk
that failed twice, a cluster that cannot be used, finished chunks of another job.

A branch of the error tree of :mod:`usar_arm.core.errors`: the errors of the layer above the
arm's pipeline, raised only there; each carries its evidence as attributes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from usar_arm.core.errors import (
    EXIT_UNAVAILABLE,
    EXIT_WORKER_FAILED,
    IKError,
    InvalidInputError,
    UsarArmError,
    aside,
)


@dataclass(eq=False, repr=False)
class ChunkFailedError(UsarArmError):
    """A chunk of a distributed job failed twice (its worker died or raised); the chunks done
    so far are kept, and ``--resume`` continues from them."""

    exit_code = EXIT_WORKER_FAILED
    chunk: int
    attempts: int
    reason: str

    def message(self) -> str:
        """This error's text, from its evidence."""
        return (f"chunk {self.chunk} failed {self.attempts} times ({self.reason}); the "
                "finished chunks are kept: run again with --resume to continue")


@dataclass(eq=False, repr=False)
class ClusterUnavailableError(UsarArmError):
    """The execution backend cannot be used: a Ray cluster that does not answer, or Ray not
    installed."""

    exit_code = EXIT_UNAVAILABLE
    address: str
    reason: str

    def message(self) -> str:
        """This error's text, from its evidence."""
        return f"cannot use the Ray cluster at '{self.address}': {self.reason}"


@dataclass(eq=False, repr=False)
class ResumeMismatchError(InvalidInputError):
    """``--resume`` found finished chunks of another job in the output folder (another robot,
    scene, problems file or setting): they are not used, and nothing is computed.

    Attributes:
        folder: the folder of the chunks. found_key, key: the kept job's key and this job's.
        differences: what differs (e.g. ``problems``, ``settings``), empty when the kept job
            does not say.
    """

    folder: str
    found_key: str | None
    key: str
    differences: Sequence[str] = ()

    def message(self) -> str:
        """This error's text, from its evidence."""
        what = (f"its {' and '.join(self.differences)} differ" if self.differences
                else "the robot, scene, input or settings differ")
        return (f"{self.folder} holds finished chunks of another job ({what}; kept key "
                f"{self.found_key}, this job's {self.key}): they would give another job's "
                "answers. Run without --resume to start over, or resume with the same input "
                "and settings")


@dataclass(eq=False, repr=False)
class MapTooLargeError(InvalidInputError):
    """A reachability map would not fit in this machine's memory; nothing was computed."""

    voxels: int
    need_bytes: int
    available_bytes: int
    resolution_that_fits_m: float

    def message(self) -> str:
        """This error's text, from its evidence."""
        return (f"a map of {self.voxels:,} voxels needs about {self.need_bytes / 2**30:.1f} "
                f"GiB, more than half of the {self.available_bytes / 2**30:.1f} GiB "
                f"available; use a resolution of at least {self.resolution_that_fits_m:g} m "
                "(or restrict the map)")


@dataclass(eq=False, repr=False)
class UnreachableTargetError(IKError):
    """A target pose of a placement study is reachable (collision-free) from no candidate
    base; the others may be."""

    target: str
    candidates: int
    detail: str = ""

    def message(self) -> str:
        """This error's text, from its evidence."""
        return (f"target '{self.target}' is reachable collision-free from none of the "
                f"{self.candidates} candidate base poses" + aside(self.detail))
