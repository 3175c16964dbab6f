"""The usar-arm error tree.

Every failure the library reports is an exception of this tree: its root (:class:`UsarArmError`:
the exit codes, and the one way an error declares its evidence) and the errors of the arm's
pipeline, from the wire to an executed motion, are here. The other branches are cut by who
raises them: a ground vehicle's (:mod:`.vehicle_errors`), workspace jobs' (:mod:`.job_errors`),
a carried body's (:mod:`.attach_errors`) and a physical cell's (:mod:`.cell_errors`). Each
carries its evidence as attributes (the offending line, the joint, the numbers, the names a user
could have meant) and a message that says what was wrong and what was expected. Each class also
names the process exit code the CLI uses for it, so that a script can tell failures apart
without parsing text.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, fields

# Exit codes of the `usar-arm` command (documented in `usar-arm --help`).
EXIT_OK = 0
EXIT_USAGE = 2
EXIT_NO_IK = 3
EXIT_NO_PLAN = 4
EXIT_IN_COLLISION = 5
EXIT_EXECUTION_ABORTED = 6
EXIT_UNKNOWN_ROBOT = 10
EXIT_UNKNOWN_START = 11
EXIT_CONNECTION_LOST = 12
EXIT_BAD_DESCRIPTION = 13
EXIT_WORKER_FAILED = 14
EXIT_INVALID_INPUT = 65  # sysexits EX_DATAERR
EXIT_UNAVAILABLE = 69  # sysexits EX_UNAVAILABLE
EXIT_INTERNAL = 70  # sysexits EX_SOFTWARE
EXIT_INTERRUPTED = 130


def names_or_none(names: Sequence[str]) -> str:
    """Names for a message, comma-separated, or ``(none)``."""
    return ", ".join(names) if names else "(none)"


def aside(detail: str) -> str:
    """`` (detail)``, to follow a message, or nothing when there is no detail."""
    return f" ({detail})" if detail else ""


def _restored(cls: type[UsarArmError], args: tuple[object, ...], evidence: dict[str, object]
              ) -> UsarArmError:
    """An error rebuilt from its text and attributes, its constructor not called (pickle)."""
    error = cls.__new__(cls, *args)
    error.args = args
    error.__dict__.update(evidence)
    return error


class UsarArmError(Exception):
    """Base class of every error usar-arm raises on purpose.

    An error that carries evidence declares it once, as the fields of a dataclass
    (``@dataclass(eq=False, repr=False)``: equality and repr stay the exception's), and says it
    in :meth:`message`. The generated constructor takes the fields in order and stores each as
    an attribute; :meth:`__post_init__` keeps a field declared ``Sequence[...]`` as a tuple
    and one declared ``dict[...]`` as a copy (the evidence is what the caller had when it
    raised), then makes the message the exception's text. An error without evidence takes its
    message as its only argument. Pickled (a worker's error on its way to the parent), an
    error comes back with its text and every attribute, its constructor not called again.
    """

    exit_code: int = EXIT_INTERNAL

    def __post_init__(self) -> None:
        for field in fields(self):  # type: ignore[arg-type]
            declared = str(field.type)
            if "Sequence[" in declared:
                setattr(self, field.name, tuple(getattr(self, field.name)))
            elif declared.startswith("dict["):
                setattr(self, field.name, dict(getattr(self, field.name)))
        super().__init__(self.message())

    def message(self) -> str:
        """What was wrong and what was expected, from the evidence (an error with evidence says
        it here; one without has its text as its argument)."""
        return " ".join(str(a) for a in self.args)

    def __reduce__(self) -> tuple[object, ...]:
        return (_restored, (type(self), self.args, dict(self.__dict__)))


# --------------------------------------------------------------------------- input and files


class InvalidInputError(UsarArmError):
    """A value given by the user (argument, file content) is not what was expected."""

    exit_code = EXIT_INVALID_INPUT


@dataclass(eq=False, repr=False)
class FileFormatError(InvalidInputError):
    """A file (scene, trajectory, limits table) has an error at a known place."""

    path: str
    problem: str
    line: int | None = None
    field: str | None = None

    def message(self) -> str:
        where = self.path if self.line is None else f"{self.path}:{self.line}"
        if self.field:
            where += f" (field '{self.field}')"
        return f"{where}: {self.problem}"


# --------------------------------------------------------------------------- the wire


@dataclass(eq=False, repr=False)
class ProtocolError(UsarArmError):
    """A line is not USARSim: not UTF-8 text, control characters, longer than the line limit,
    or not following the grammar.

    Attributes:
        line: the offending line, without its terminator.
        position: 0-based character index in ``line`` where the problem was found.
        reason: what was wrong and what was expected there.
    """

    exit_code = EXIT_BAD_DESCRIPTION
    line: str
    position: int
    reason: str

    def message(self) -> str:
        line, position = self.line, self.position
        start = 0 if position < 150 else position - 100  # show the text around the problem
        shown = line[start:start + 200]
        pointer = " " * (position - start) + "^"
        if start > 0:
            shown, pointer = "..." + shown, "   " + pointer
        if start + 200 < len(line):
            shown += "..."
        return f"{self.reason} at column {position + 1}:\n  {shown}\n  {pointer}"


@dataclass(eq=False, repr=False)
class ConnectionFailedError(UsarArmError):
    """No TCP connection could be made to the USARSim server."""

    exit_code = EXIT_UNAVAILABLE
    host: str
    port: int
    reason: str

    def message(self) -> str:
        return (f"cannot connect to a USARSim server at {self.host}:{self.port}: {self.reason}. "
                f"Is the simulator running? (start one with `usar-arm sim --port {self.port}`, "
                f"or leave out --host to use the embedded simulator)")


@dataclass(eq=False, repr=False)
class ResponseTimeoutError(UsarArmError):
    """The server did not send what was waited for within the timeout."""

    exit_code = EXIT_UNAVAILABLE
    waiting_for: str
    timeout_s: float
    hint: str = ""

    def message(self) -> str:
        text = f"no {self.waiting_for} within {self.timeout_s:g} s"
        return text + (f": {self.hint}" if self.hint else "")


class UnknownComponentError(ResponseTimeoutError):
    """A GETCONF/GETGEO matched nothing (UDK then sends no reply at all): a timeout whose hint
    names the request and the components the server has reported."""

    def __init__(self, request: str, timeout_s: float, known: Sequence[str]):
        self.request = request
        self.known = tuple(known)
        super().__init__(
            f"reply to `{request}`",
            timeout_s,
            "USARSim sends nothing when no component matches the Type/Name asked for. "
            f"Components this server has reported: {names_or_none(self.known)}",
        )


@dataclass(eq=False, repr=False)
class ConnectionLostError(UsarArmError):
    """The server closed the connection (or it broke) while the client still needed it."""

    exit_code = EXIT_CONNECTION_LOST
    while_doing: str
    detail: str = ""

    def message(self) -> str:
        return (f"the USARSim server closed the connection while {self.while_doing}"
                + aside(self.detail))


# --------------------------------------------------------------------------- discovery


@dataclass(eq=False, repr=False)
class UnknownRobotError(UsarArmError):
    """The server did not spawn the requested robot class."""

    exit_code = EXIT_UNKNOWN_ROBOT
    class_name: str
    known: Sequence[str] = ()
    detail: str = ""

    def message(self) -> str:
        text = f"no robot of class '{self.class_name}' appeared" + aside(self.detail)
        if self.known:
            text += f"; robot classes the server offers: {names_or_none(self.known)}"
        return text


@dataclass(eq=False, repr=False)
class UnknownStartError(UsarArmError):
    """The requested start position is not one the server offers."""

    exit_code = EXIT_UNKNOWN_START
    start: str
    known: Sequence[str]

    def message(self) -> str:
        known = names_or_none(self.known)
        return f"unknown start position '{self.start}'; the server offers: {known}"


class DescriptionError(UsarArmError):
    """What the server described cannot be turned into a valid robot description."""

    exit_code = EXIT_BAD_DESCRIPTION


@dataclass(eq=False, repr=False)
class ValidationError(DescriptionError):
    """A generated description failed one or more checks; every problem is listed."""

    subject: str
    problems: Sequence[str]

    def message(self) -> str:
        lines = "\n".join(f"  - {p}" for p in self.problems)
        return f"{self.subject} failed {len(self.problems)} check(s):\n{lines}"


@dataclass(eq=False, repr=False)
class RobotStructureError(DescriptionError):
    """A URDF (+ SRDF, options) has no serial chain to plan: a floating or planar joint, a
    closed loop, a branched robot without a group, an unknown base or tip link."""

    what: str
    where: str
    expected: str

    def message(self) -> str:
        return f"{self.where}: {self.what}; expected {self.expected}"


# --------------------------------------------------------------------------- kinematics


class IKError(UsarArmError):
    """No inverse-kinematics solution; subclasses say why."""

    exit_code = EXIT_NO_IK


@dataclass(eq=False, repr=False)
class UnreachableError(IKError):
    """The target is outside the arm's workspace (or no solver converged)."""

    distance_m: float
    detail: str = ""

    def message(self) -> str:
        return (f"target pose is unreachable: out of reach by {self.distance_m * 1000:.1f} mm"
                + aside(self.detail))


@dataclass(eq=False, repr=False)
class JointLimitError(IKError):
    """Solutions exist, but each needs a joint beyond its limits."""

    joint: str
    value: float
    lower: float
    upper: float

    @property
    def excess(self) -> float:
        """How far (rad or m) ``value`` lies outside [lower, upper]."""
        return self.value - self.upper if self.value > self.upper else self.lower - self.value

    def message(self) -> str:
        return (f"every solution violates a joint limit; closest: {self.joint} = "
                f"{self.value:.4f} is {self.excess:.4f} outside [{self.lower:.4f}, "
                f"{self.upper:.4f}]")


@dataclass(eq=False, repr=False)
class AllSolutionsInCollisionError(IKError):
    """Every IK solution inside the limits is in collision."""

    exit_code = EXIT_IN_COLLISION
    n_solutions: int
    pairs: Sequence[tuple[str, str]]

    def message(self) -> str:
        shown = ", ".join(f"{a}–{b}" for a, b in self.pairs[:6])
        return (f"all {self.n_solutions} IK solution(s) inside the joint limits are in "
                f"collision (contacts: {shown})")


# --------------------------------------------------------------------------- planning


class PlanningError(UsarArmError):
    """No motion could be planned; subclasses say why."""

    exit_code = EXIT_NO_PLAN


@dataclass(eq=False, repr=False)
class _EndInCollisionError(PlanningError):
    """An end of the motion (``end``: start or goal) is in collision; ``pairs`` are the
    colliding (link or obstacle) name pairs."""

    exit_code = EXIT_IN_COLLISION
    end = ""
    pairs: Sequence[tuple[str, str]]

    def message(self) -> str:
        shown = ", ".join(f"{a}–{b}" for a, b in self.pairs)
        return f"the {self.end} configuration is in collision: {shown}"


class StartInCollisionError(_EndInCollisionError):
    """The start configuration is in collision."""

    end = "start"


class GoalInCollisionError(_EndInCollisionError):
    """The goal configuration is in collision."""

    end = "goal"


@dataclass(eq=False, repr=False)
class OutOfLimitsError(PlanningError):
    """A start or goal configuration lies outside the joint limits."""

    exit_code = EXIT_INVALID_INPUT
    what: str
    joint: str
    value: float
    lower: float
    upper: float

    def message(self) -> str:
        return (f"the {self.what} configuration puts {self.joint} at {self.value:.4f}, "
                f"outside its limits [{self.lower:.4f}, {self.upper:.4f}]")


@dataclass(eq=False, repr=False)
class NoPathError(PlanningError):
    """The planner found no collision-free path within its budget."""

    planner: str
    time_limit_s: float
    detail: str = ""

    def message(self) -> str:
        return (f"{self.planner} found no collision-free path within {self.time_limit_s:g} s"
                + aside(self.detail))


@dataclass(eq=False, repr=False)
class LinBlockedError(PlanningError):
    """A straight-line (LIN) motion cannot be followed."""

    fraction: float
    point_m: Iterable[float]
    reason: str

    def __post_init__(self) -> None:
        self.point_m = tuple(float(x) for x in self.point_m)
        super().__post_init__()

    def message(self) -> str:
        x, y, z = self.point_m
        return (f"LIN motion blocked at {self.fraction * 100:.1f} % of the line, tool0 at "
                f"({x:.4f}, {y:.4f}, {z:.4f}) m: {self.reason}")


class TimingError(PlanningError):
    """Time-parameterisation failed (limits inconsistent, Ruckig error)."""


# --------------------------------------------------------------------------- execution


@dataclass(eq=False, repr=False)
class ExecutionAbortedError(UsarArmError):
    """Execution on the arm stopped before the motion completed; the arm holds where it is."""

    exit_code = EXIT_EXECUTION_ABORTED
    reason: str
    joint: str | None = None
    error_rad: float | None = None
    at_time_s: float | None = None

    def message(self) -> str:
        text = f"execution aborted: {self.reason}"
        if self.joint is not None and self.error_rad is not None:
            text += f" ({self.joint} off by {self.error_rad:.4f})"
        if self.at_time_s is not None:
            text += f" at t = {self.at_time_s:.2f} s"
        return text + "; the arm was told to hold its current position"


# --------------------------------------------------------------------------- calibration


@dataclass(eq=False, repr=False)
class CalibrationError(UsarArmError):
    """A kinematic calibration cannot be made (too few readings, nothing identifiable, no
    convergence); nothing was written and the as-learnt description is kept."""

    exit_code = EXIT_INVALID_INPUT
    problem: str
    readings: int | None = None
    needed: int | None = None

    def message(self) -> str:
        text = f"calibration failed: {self.problem}"
        if self.readings is not None and self.needed is not None:
            text += f" ({self.readings} readings, at least {self.needed} needed)"
        return text + "; nothing was written"
