"""The usar-arm error tree.

Every failure the library reports is an exception of this tree: its root (:class:`UsarArmError`,
the exit codes) and the errors of the arm's pipeline, from the wire to an executed motion, are
here; the errors of a ground vehicle are in :mod:`.vehicle_errors` and those of workspace jobs
in :mod:`.job_errors`, beside the layers that raise them. Each carries its evidence as
attributes (the offending line, the joint, the numbers, the names a user could have meant) and a
message that says what was wrong and what was expected. Each class also names the process exit
code the CLI uses for it, so that a script can tell failures apart without parsing text.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

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


def _names(names: Sequence[str]) -> str:
    return ", ".join(names) if names else "(none)"


class UsarArmError(Exception):
    """Base class of every error usar-arm raises on purpose."""

    exit_code: int = EXIT_INTERNAL


# --------------------------------------------------------------------------- input and files


class InvalidInputError(UsarArmError):
    """A value given by the user (argument, file content) is not what was expected."""

    exit_code = EXIT_INVALID_INPUT


class FileFormatError(InvalidInputError):
    """A file (scene, trajectory, limits table) has an error at a known place."""

    def __init__(self, path: str, problem: str, line: int | None = None, field: str | None = None):
        self.path = path
        self.problem = problem
        self.line = line
        self.field = field
        where = path if line is None else f"{path}:{line}"
        if field:
            where += f" (field '{field}')"
        super().__init__(f"{where}: {problem}")


# --------------------------------------------------------------------------- the wire


class ProtocolError(UsarArmError):
    """A line is not USARSim: not UTF-8 text, control characters, longer than the line limit,
    or not following the grammar.

    Attributes:
        line: the offending line, without its terminator.
        position: 0-based character index in ``line`` where the problem was found.
        reason: what was wrong and what was expected there.
    """

    exit_code = EXIT_BAD_DESCRIPTION

    def __init__(self, line: str, position: int, reason: str):
        self.line = line
        self.position = position
        self.reason = reason
        start = 0 if position < 150 else position - 100  # show the text around the problem
        shown = line[start:start + 200]
        pointer = " " * (position - start) + "^"
        if start > 0:
            shown, pointer = "..." + shown, "   " + pointer
        if start + 200 < len(line):
            shown += "..."
        super().__init__(f"{reason} at column {position + 1}:\n  {shown}\n  {pointer}")


class ConnectionFailedError(UsarArmError):
    """No TCP connection could be made to the USARSim server."""

    exit_code = EXIT_UNAVAILABLE

    def __init__(self, host: str, port: int, reason: str):
        self.host = host
        self.port = port
        self.reason = reason
        super().__init__(
            f"cannot connect to a USARSim server at {host}:{port}: {reason}. "
            f"Is the simulator running? (start one with `usar-arm sim --port {port}`, "
            f"or leave out --host to use the embedded simulator)"
        )


class ResponseTimeoutError(UsarArmError):
    """The server did not send what was waited for within the timeout."""

    exit_code = EXIT_UNAVAILABLE

    def __init__(self, waiting_for: str, timeout_s: float, hint: str = ""):
        self.waiting_for = waiting_for
        self.timeout_s = timeout_s
        self.hint = hint
        text = f"no {waiting_for} within {timeout_s:g} s"
        super().__init__(text + (f": {hint}" if hint else ""))


class UnknownComponentError(ResponseTimeoutError):
    """A GETCONF/GETGEO matched nothing (UDK then sends no reply at all)."""

    def __init__(self, request: str, timeout_s: float, known: Sequence[str]):
        self.request = request
        self.known = tuple(known)
        super().__init__(
            f"reply to `{request}`",
            timeout_s,
            "USARSim sends nothing when no component matches the Type/Name asked for. "
            f"Components this server has reported: {_names(self.known)}",
        )


class ConnectionLostError(UsarArmError):
    """The server closed the connection (or it broke) while the client still needed it."""

    exit_code = EXIT_CONNECTION_LOST

    def __init__(self, while_doing: str, detail: str = ""):
        self.while_doing = while_doing
        self.detail = detail
        msg = f"the USARSim server closed the connection while {while_doing}"
        super().__init__(msg + (f" ({detail})" if detail else ""))


# --------------------------------------------------------------------------- discovery


class UnknownRobotError(UsarArmError):
    """The server did not spawn the requested robot class."""

    exit_code = EXIT_UNKNOWN_ROBOT

    def __init__(self, class_name: str, known: Sequence[str] = (), detail: str = ""):
        self.class_name = class_name
        self.known = tuple(known)
        text = f"no robot of class '{class_name}' appeared"
        if detail:
            text += f" ({detail})"
        if self.known:
            text += f"; robot classes the server offers: {_names(self.known)}"
        super().__init__(text)


class UnknownStartError(UsarArmError):
    """The requested start position is not one the server offers."""

    exit_code = EXIT_UNKNOWN_START

    def __init__(self, start: str, known: Sequence[str]):
        self.start = start
        self.known = tuple(known)
        super().__init__(
            f"unknown start position '{start}'; the server offers: {_names(self.known)}"
        )


class DescriptionError(UsarArmError):
    """What the server described cannot be turned into a valid robot description."""

    exit_code = EXIT_BAD_DESCRIPTION


class ValidationError(DescriptionError):
    """A generated description failed one or more checks; every problem is listed."""

    def __init__(self, subject: str, problems: Sequence[str]):
        self.subject = subject
        self.problems = tuple(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        super().__init__(f"{subject} failed {len(self.problems)} check(s):\n{lines}")


class RobotStructureError(DescriptionError):
    """A URDF (+ SRDF, options) has no serial chain to plan: a floating or planar joint, a
    closed loop, a branched robot without a group, an unknown base or tip link."""

    def __init__(self, what: str, where: str, expected: str):
        self.what, self.where, self.expected = what, where, expected
        super().__init__(f"{where}: {what}; expected {expected}")


# --------------------------------------------------------------------------- kinematics


class IKError(UsarArmError):
    """No inverse-kinematics solution; subclasses say why."""

    exit_code = EXIT_NO_IK


class UnreachableError(IKError):
    """The target is outside the arm's workspace (or no solver converged)."""

    def __init__(self, distance_m: float, detail: str = ""):
        self.distance_m = distance_m
        text = f"target pose is unreachable: out of reach by {distance_m * 1000:.1f} mm"
        super().__init__(text + (f" ({detail})" if detail else ""))


class JointLimitError(IKError):
    """Solutions exist, but each needs a joint beyond its limits."""

    def __init__(self, joint: str, value: float, lower: float, upper: float):
        self.joint = joint
        self.value = value
        self.lower = lower
        self.upper = upper
        excess = value - upper if value > upper else lower - value
        self.excess = excess
        super().__init__(
            f"every solution violates a joint limit; closest: {joint} = {value:.4f} is "
            f"{excess:.4f} outside [{lower:.4f}, {upper:.4f}]"
        )


class AllSolutionsInCollisionError(IKError):
    """Every IK solution inside the limits is in collision."""

    exit_code = EXIT_IN_COLLISION

    def __init__(self, n_solutions: int, pairs: Sequence[tuple[str, str]]):
        self.n_solutions = n_solutions
        self.pairs = tuple(pairs)
        shown = ", ".join(f"{a}–{b}" for a, b in self.pairs[:6])
        super().__init__(
            f"all {n_solutions} IK solution(s) inside the joint limits are in collision "
            f"(contacts: {shown})"
        )


# --------------------------------------------------------------------------- planning


class PlanningError(UsarArmError):
    """No motion could be planned; subclasses say why."""

    exit_code = EXIT_NO_PLAN


class _EndInCollisionError(PlanningError):
    """An end of the motion (``end``: start or goal) is in collision; ``pairs`` are the
    colliding (link or obstacle) name pairs."""

    exit_code = EXIT_IN_COLLISION
    end = ""

    def __init__(self, pairs: Sequence[tuple[str, str]]):
        self.pairs = tuple(pairs)
        shown = ", ".join(f"{a}–{b}" for a, b in self.pairs)
        super().__init__(f"the {self.end} configuration is in collision: {shown}")


class StartInCollisionError(_EndInCollisionError):
    """The start configuration is in collision."""

    end = "start"


class GoalInCollisionError(_EndInCollisionError):
    """The goal configuration is in collision."""

    end = "goal"


class OutOfLimitsError(PlanningError):
    """A start or goal configuration lies outside the joint limits."""

    exit_code = EXIT_INVALID_INPUT

    def __init__(self, what: str, joint: str, value: float, lower: float, upper: float):
        self.what = what
        self.joint = joint
        self.value = value
        self.lower = lower
        self.upper = upper
        super().__init__(
            f"the {what} configuration puts {joint} at {value:.4f}, outside its limits "
            f"[{lower:.4f}, {upper:.4f}]"
        )


class NoPathError(PlanningError):
    """The planner found no collision-free path within its budget."""

    def __init__(self, planner: str, time_limit_s: float, detail: str = ""):
        self.planner = planner
        self.time_limit_s = time_limit_s
        text = f"{planner} found no collision-free path within {time_limit_s:g} s"
        super().__init__(text + (f" ({detail})" if detail else ""))


class LinBlockedError(PlanningError):
    """A straight-line (LIN) motion cannot be followed."""

    def __init__(self, fraction: float, point_m: Iterable[float], reason: str):
        self.fraction = fraction
        self.point_m = tuple(float(x) for x in point_m)
        self.reason = reason
        x, y, z = self.point_m
        super().__init__(
            f"LIN motion blocked at {fraction * 100:.1f} % of the line, tool0 at "
            f"({x:.4f}, {y:.4f}, {z:.4f}) m: {reason}"
        )


class TimingError(PlanningError):
    """Time-parameterisation failed (limits inconsistent, Ruckig error)."""


class AttachError(InvalidInputError):
    """An object cannot be attached to (or detached from) the arm: an unknown link, a name
    that is already a link or a carried object, an object the scene lacks, nothing carried
    by that name.

    Attributes:
        body: the object's name. problem: what was wrong. known: the names that would have
            been accepted (links, objects, carried bodies).
    """

    def __init__(self, body: str, problem: str, known: Sequence[str] = ()):
        self.body = body
        self.problem = problem
        self.known = tuple(known)
        text = f"cannot attach '{body}': {problem}"
        if self.known:
            text += f" (known: {_names(self.known)})"
        super().__init__(text)


class AttachedCollisionError(PlanningError):
    """An object to attach is in collision, at the configuration it is attached at, with
    something other than its parent and touch links.

    Attributes:
        body: the object's name. contacts: (body, other, depth m) of each pair in contact.
    """

    exit_code = EXIT_IN_COLLISION

    def __init__(self, body: str, contacts: Sequence[tuple[str, str, float]]):
        self.body = body
        self.contacts = tuple(contacts)
        shown = ", ".join(f"{a}–{b} ({d * 1000:.1f} mm deep)" for a, b, d in self.contacts)
        super().__init__(f"'{body}' is in collision where it would be attached: {shown}; "
                         "name the links it may touch (touch_links) or attach it elsewhere")


# --------------------------------------------------------------------------- execution


class ExecutionAbortedError(UsarArmError):
    """Execution on the arm stopped before the motion completed; the arm holds where it is."""

    exit_code = EXIT_EXECUTION_ABORTED

    def __init__(self, reason: str, joint: str | None = None, error_rad: float | None = None,
                 at_time_s: float | None = None):
        self.reason = reason
        self.joint = joint
        self.error_rad = error_rad
        self.at_time_s = at_time_s
        text = f"execution aborted: {reason}"
        if joint is not None and error_rad is not None:
            text += f" ({joint} off by {error_rad:.4f})"
        if at_time_s is not None:
            text += f" at t = {at_time_s:.2f} s"
        super().__init__(text + "; the arm was told to hold its current position")


# --------------------------------------------------------------------------- calibration


class CalibrationError(UsarArmError):
    """A kinematic calibration cannot be made (too few readings, nothing identifiable, no
    convergence); nothing was written and the as-learnt description is kept."""

    exit_code = EXIT_INVALID_INPUT

    def __init__(self, problem: str, readings: int | None = None,
                 needed: int | None = None):
        self.problem = problem
        self.readings = readings
        self.needed = needed
        text = f"calibration failed: {problem}"
        if readings is not None and needed is not None:
            text += f" ({readings} readings, at least {needed} needed)"
        super().__init__(text + "; nothing was written")
