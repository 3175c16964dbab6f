"""Pure pursuit along a polyline of waypoints, and velocity scripts: what to command next.

Pure pursuit (Coulter 1992): the vehicle steers onto the circle through its position that
touches its heading and passes through the *lookahead point*, the point of the path a lookahead
distance beyond the vehicle's projection on it. The curvature is ``2 y / d^2`` (``y`` the
lookahead point's lateral offset in the vehicle frame, ``d`` its distance). A point further off
the heading than ``turn_in_place_rad`` is faced first by turning on the spot, which a
skid-steered vehicle can do: a skidding vehicle turns far less than its wheel speeds say (the
embedded P3AT about a fifth), so arcs alone would overshoot every corner. All in REP-103 (x
forward, y left, yaw counter-clockwise), metres, seconds, radians. Pure: no wire, no clock.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from usar_arm.core.errors import InvalidInputError


@dataclass(frozen=True)
class PursuitOptions:
    """Pure pursuit settings.

    Attributes:
        lookahead_m: distance (m) of the lookahead point beyond the vehicle's projection.
        max_speed_mps: forward speed (m/s) asked for; the wheel limits may lower it.
        goal_tolerance_m: the last waypoint counts as reached within this distance (m).
        turn_rate_rps: yaw rate (rad/s) of a turn on the spot.
        turn_in_place_rad: the lookahead point's bearing (rad) beyond which the vehicle stops
            and turns on the spot.
    """

    lookahead_m: float = 0.5
    max_speed_mps: float = 0.5
    goal_tolerance_m: float = 0.1
    turn_rate_rps: float = 1.0
    turn_in_place_rad: float = 0.5

    def __post_init__(self) -> None:
        for name in ("lookahead_m", "max_speed_mps", "goal_tolerance_m", "turn_rate_rps",
                     "turn_in_place_rad"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InvalidInputError(f"pursuit {name} must be a positive number, got {value}")


@dataclass(frozen=True)
class Segment:
    """One step of a velocity script: hold ``v`` (m/s) and ``w`` (rad/s) for ``duration_s``."""

    duration_s: float
    v: float
    w: float


class PurePursuit:
    """Follows the polyline from ``start`` through ``waypoints`` (m, REP-103 map frame).

    Call :meth:`command` with each new pose; it returns (v m/s, w rad/s), and (0, 0) once
    :attr:`done`.
    """

    def __init__(self, start: tuple[float, float], waypoints: Sequence[tuple[float, float]],
                 options: PursuitOptions):
        if not waypoints:
            raise InvalidInputError("pure pursuit needs at least one waypoint")
        self.points = [tuple(map(float, start)), *(tuple(map(float, p)) for p in waypoints)]
        self.options = options
        self.segment = 0
        self.done = False
        lengths = [math.dist(a, b) for a, b in zip(self.points, self.points[1:], strict=False)]
        self.cumulative = [0.0]
        for length in lengths:
            self.cumulative.append(self.cumulative[-1] + length)

    @property
    def length_m(self) -> float:
        """Length (m) of the whole path."""
        return self.cumulative[-1]

    def progress_m(self, x: float, y: float) -> float:
        """Arc length (m) of the vehicle's projection on the path's current segment."""
        return self._project(x, y)[0]

    def _project(self, x: float, y: float) -> tuple[float, float]:
        """(arc length of the projection, its parameter on the current segment in [0, 1])."""
        a, b = self.points[self.segment], self.points[self.segment + 1]
        dx, dy = b[0] - a[0], b[1] - a[1]
        span = dx * dx + dy * dy
        u = 0.0 if span == 0 else max(0.0, min(1.0, ((x - a[0]) * dx + (y - a[1]) * dy) / span))
        return self.cumulative[self.segment] + u * math.sqrt(span), u

    def _point_at(self, s: float) -> tuple[float, float]:
        s = min(s, self.length_m)
        k = max(i for i, c in enumerate(self.cumulative[:-1]) if c <= s)
        a, b = self.points[k], self.points[k + 1]
        length = self.cumulative[k + 1] - self.cumulative[k]
        u = 0.0 if length == 0 else (s - self.cumulative[k]) / length
        return a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])

    def command(self, x: float, y: float, yaw: float) -> tuple[float, float]:
        """(v m/s, w rad/s) toward the lookahead point from pose (x, y m, yaw rad)."""
        opts = self.options
        goal = self.points[-1]
        if self.done:
            return 0.0, 0.0
        s, u = self._project(x, y)
        while self.segment < len(self.points) - 2 and (
                u >= 1.0 or self.cumulative[self.segment + 1] - s < opts.lookahead_m):
            self.segment += 1
            s, u = self._project(x, y)
        if self.segment == len(self.points) - 2 and \
                math.dist((x, y), goal) <= opts.goal_tolerance_m:
            self.done = True  # (on the last leg only: a closed loop ends where it began)
            return 0.0, 0.0
        tx, ty = self._point_at(s + opts.lookahead_m)
        c, sn = math.cos(yaw), math.sin(yaw)
        ahead = c * (tx - x) + sn * (ty - y)
        lateral = -sn * (tx - x) + c * (ty - y)
        if abs(math.atan2(lateral, ahead)) > opts.turn_in_place_rad:
            return 0.0, math.copysign(opts.turn_rate_rps, lateral)
        d2 = ahead * ahead + lateral * lateral
        v = min(opts.max_speed_mps, max(self.length_m - s, math.dist((x, y), goal)))
        return v, v * 2 * lateral / max(d2, 1e-9)


def script_command(segments: Sequence[Segment], t: float) -> tuple[float, float] | None:
    """(v, w) of the segment running ``t`` s after the script's start; None after its end."""
    end = 0.0
    for seg in segments:
        end += seg.duration_s
        if t < end:
            return seg.v, seg.w
    return None
