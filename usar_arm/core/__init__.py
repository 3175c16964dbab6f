"""The foundation every layer stands on (numpy only): typed errors with their evidence and exit
codes (:mod:`.errors`), rotations and frames (:mod:`.spatial`), the data model of an arm in SI
units and REP-103 frames (:mod:`.model`), atomic file writes (:mod:`.fileio`), safe YAML
(:mod:`.yamlio`), numbers written with the precision they mean (:mod:`.precision`) and the
version (:mod:`.version`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.core.errors import (
        AllSolutionsInCollisionError,
        CalibrationError,
        ConnectionFailedError,
        ConnectionLostError,
        DescriptionError,
        ExecutionAbortedError,
        FileFormatError,
        GoalInCollisionError,
        IKError,
        InvalidInputError,
        JointLimitError,
        LinBlockedError,
        MapTooLargeError,
        NoPathError,
        OutOfLimitsError,
        PlanningError,
        ProtocolError,
        ResponseTimeoutError,
        RobotStructureError,
        StartInCollisionError,
        TimingError,
        UnknownComponentError,
        UnknownRobotError,
        UnknownStartError,
        UnreachableError,
        UnreachableTargetError,
        UsarArmError,
        ValidationError,
    )
    from usar_arm.core.fileio import write_atomic, write_tree_atomic
    from usar_arm.core.job_errors import (
        ChunkFailedError,
        ClusterUnavailableError,
        ResumeMismatchError,
    )
    from usar_arm.core.model import Joint, JointLimits, JointType, KinematicChain, Link, Origin
    from usar_arm.core.spatial import (
        invert,
        matrix_to_rpy,
        rotation_angle,
        rpy_to_matrix,
        transform,
        transform_from_xyz_rpy,
    )
    from usar_arm.core.version import __version__
    from usar_arm.core.yamlio import load_yaml, loads_yaml

_HOMES = {
    "errors": ("AllSolutionsInCollisionError", "CalibrationError", "ConnectionFailedError",
        "ConnectionLostError",
        "DescriptionError", "ExecutionAbortedError", "FileFormatError", "GoalInCollisionError",
        "IKError", "InvalidInputError", "JointLimitError", "LinBlockedError", "MapTooLargeError",
        "NoPathError", "OutOfLimitsError", "PlanningError", "ProtocolError",
        "ResponseTimeoutError", "RobotStructureError",
        "StartInCollisionError", "TimingError",
        "UnknownComponentError", "UnknownRobotError", "UnknownStartError", "UnreachableError",
        "UnreachableTargetError", "UsarArmError", "ValidationError"),
    "job_errors": ("ChunkFailedError", "ClusterUnavailableError", "ResumeMismatchError"),
    "fileio": ("write_atomic", "write_tree_atomic"),
    "model": ("Joint", "JointLimits", "JointType", "KinematicChain", "Link", "Origin"),
    "spatial": ("invert", "matrix_to_rpy", "rotation_angle", "rpy_to_matrix", "transform",
        "transform_from_xyz_rpy"),
    "version": ("__version__",),
    "yamlio": ("load_yaml", "loads_yaml"),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["AllSolutionsInCollisionError", "CalibrationError", "ChunkFailedError",
           "ClusterUnavailableError", "ConnectionFailedError", "ConnectionLostError",
           "DescriptionError", "ExecutionAbortedError", "FileFormatError", "GoalInCollisionError",
           "IKError", "InvalidInputError", "Joint", "JointLimitError", "JointLimits", "JointType",
           "KinematicChain", "LinBlockedError", "Link", "MapTooLargeError",
           "NoPathError",
           "Origin", "OutOfLimitsError", "PlanningError", "ProtocolError", "ResponseTimeoutError",
           "ResumeMismatchError", "RobotStructureError", "StartInCollisionError", "TimingError",
           "UnknownComponentError",
           "UnknownRobotError", "UnknownStartError", "UnreachableError", "UnreachableTargetError",
           "UsarArmError", "ValidationError", "__version__", "invert", "load_yaml", "loads_yaml",
           "matrix_to_rpy", "rotation_angle", "rpy_to_matrix", "transform",
           "transform_from_xyz_rpy", "write_atomic", "write_tree_atomic"]

__getattr__ = exports(__name__, _HOMES)
