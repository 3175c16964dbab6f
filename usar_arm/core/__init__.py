"""The foundation every layer stands on (numpy only): typed errors with their evidence and exit
codes (:mod:`.errors`), rotations and frames (:mod:`.spatial`), the data model of an arm in SI
units and REP-103 frames (:mod:`.model`), atomic file writes (:mod:`.fileio`), safe YAML
(:mod:`.yamlio`), numbers written with the precision they mean (:mod:`.precision`) and the
version (:mod:`.version`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.core.errors import AllSolutionsInCollisionError as AllSolutionsInCollisionError
    from usar_arm.core.errors import CalibrationError as CalibrationError
    from usar_arm.core.errors import ConnectionFailedError as ConnectionFailedError
    from usar_arm.core.errors import ConnectionLostError as ConnectionLostError
    from usar_arm.core.errors import DescriptionError as DescriptionError
    from usar_arm.core.errors import ExecutionAbortedError as ExecutionAbortedError
    from usar_arm.core.errors import FileFormatError as FileFormatError
    from usar_arm.core.errors import GoalInCollisionError as GoalInCollisionError
    from usar_arm.core.errors import IKError as IKError
    from usar_arm.core.errors import InvalidInputError as InvalidInputError
    from usar_arm.core.errors import JointLimitError as JointLimitError
    from usar_arm.core.errors import LinBlockedError as LinBlockedError
    from usar_arm.core.errors import NoPathError as NoPathError
    from usar_arm.core.errors import OutOfLimitsError as OutOfLimitsError
    from usar_arm.core.errors import PlanningError as PlanningError
    from usar_arm.core.errors import ProtocolError as ProtocolError
    from usar_arm.core.errors import ResponseTimeoutError as ResponseTimeoutError
    from usar_arm.core.errors import RobotStructureError as RobotStructureError
    from usar_arm.core.errors import StartInCollisionError as StartInCollisionError
    from usar_arm.core.errors import TimingError as TimingError
    from usar_arm.core.errors import UnknownComponentError as UnknownComponentError
    from usar_arm.core.errors import UnknownRobotError as UnknownRobotError
    from usar_arm.core.errors import UnknownStartError as UnknownStartError
    from usar_arm.core.errors import UnreachableError as UnreachableError
    from usar_arm.core.errors import UsarArmError as UsarArmError
    from usar_arm.core.errors import ValidationError as ValidationError
    from usar_arm.core.fileio import write_atomic as write_atomic
    from usar_arm.core.fileio import write_tree_atomic as write_tree_atomic
    from usar_arm.core.job_errors import ChunkFailedError as ChunkFailedError
    from usar_arm.core.job_errors import ClusterUnavailableError as ClusterUnavailableError
    from usar_arm.core.job_errors import MapTooLargeError as MapTooLargeError
    from usar_arm.core.job_errors import ResumeMismatchError as ResumeMismatchError
    from usar_arm.core.job_errors import UnreachableTargetError as UnreachableTargetError
    from usar_arm.core.model import Joint as Joint
    from usar_arm.core.model import JointLimits as JointLimits
    from usar_arm.core.model import JointType as JointType
    from usar_arm.core.model import KinematicChain as KinematicChain
    from usar_arm.core.model import Link as Link
    from usar_arm.core.model import Origin as Origin
    from usar_arm.core.spatial import invert as invert
    from usar_arm.core.spatial import matrix_to_rpy as matrix_to_rpy
    from usar_arm.core.spatial import rotation_angle as rotation_angle
    from usar_arm.core.spatial import rpy_to_matrix as rpy_to_matrix
    from usar_arm.core.spatial import transform as transform
    from usar_arm.core.spatial import transform_from_xyz_rpy as transform_from_xyz_rpy
    from usar_arm.core.version import __version__ as __version__
    from usar_arm.core.yamlio import load_yaml as load_yaml
    from usar_arm.core.yamlio import loads_yaml as loads_yaml

__getattr__, __dir__, __all__ = exports(__name__, __file__)
