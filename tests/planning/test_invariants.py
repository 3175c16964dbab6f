"""Seeded planning problems over every scene: what comes back is safe, what fails says why.

Each problem (KR60 and the 7-joint Fanuc on its rail; PTP stopping and blending, LIN; joint and
pose goals) is drawn from a seeded generator, including deliberately hard and impossible ones:
goals in collision, poses out of reach, joints out of their limits, lines through obstacles,
budgets too small to plan in, malformed input. For every problem:

* a returned plan passes the 1 kHz re-check (:mod:`tests.planning.recheck`): no collision, every
  joint within its position, velocity, acceleration and jerk limits, on the goal (1 mm / 1 mrad
  for a pose goal), LIN on its line;
* a failure is one of the documented error classes (anything else fails the test), and a
  deliberately impossible problem fails with the class that names its reason.

The counts (per kind of problem, robot, scene and mode: tried, solved, each error class) go to
``invariants.json`` in the test's tmp folder and to stdout (``pytest -s``).
"""

from __future__ import annotations

import json
import time
from collections import Counter, defaultdict
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.planning.recheck import finite_difference_violations, recheck
from usar_arm.control.motion import MotionOptions, plan_motion
from usar_arm.core.errors import (
    GoalInCollisionError,
    IKError,
    InvalidInputError,
    LinBlockedError,
    NoPathError,
    OutOfLimitsError,
    StartInCollisionError,
    TimingError,
)
from usar_arm.core.spatial import Array, exp_so3, transform
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ompl_adapter import OmplOptions, edge_configurations
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene_file import BUILTIN, load_scene

TYPED: tuple[type[Exception], ...] = (
    InvalidInputError, OutOfLimitsError, StartInCollisionError, GoalInCollisionError, IKError,
    NoPathError, LinBlockedError, TimingError)
"""The failures :func:`plan_motion` documents (IKError with its subclasses: unreachable, joint
limit, every solution in collision). Anything else is a bug."""

TIME_LIMIT = 0.25
"""OMPL budget (s) per IK solution tried: small, so that the suite stays bounded."""

KINDS: dict[str, int] = {
    # kind: weight. Feasible-looking problems first, then the deliberately hard ones.
    "free-pair": 20,        # PTP joint goal, start and goal collision-free
    "blocked-pair": 10,     # ... whose straight joint segment is blocked (OMPL must plan)
    "random-pair": 8,       # PTP joint goal, start and goal anywhere inside the limits
    "pose": 15,             # PTP to the tool0 pose of a free configuration
    "pose-any": 4,          # PTP to the tool0 pose of any configuration
    "lin-short": 15,        # LIN: 5-50 cm and up to 0.5 rad from a free start
    "lin-long": 6,          # LIN to the tool0 pose of another free configuration
    "lin-joints": 3,        # LIN given a joint goal
    "goal-in-collision": 4,
    "unreachable": 4,       # a pose far beyond the reach (PTP or LIN)
    "out-of-limits": 3,
    "tiny-budget": 3,       # a blocked pair with a 0.1 ms budget
    "same": 2,              # the goal is the start (joint or pose, PTP or LIN)
    "bad-input": 3,         # wrong sizes, NaN, a pose that is no rigid transform
}
EXPECTED: dict[str, tuple[type[Exception], ...]] = {
    "goal-in-collision": (GoalInCollisionError,),
    "unreachable": (IKError, LinBlockedError),
    "out-of-limits": (OutOfLimitsError,),
    "tiny-budget": (NoPathError,),
    "bad-input": (InvalidInputError, OutOfLimitsError),
}
"""The only failures allowed for deliberately impossible problems."""
MUST_FAIL = {"goal-in-collision", "unreachable", "out-of-limits", "bad-input"}
MUST_SOLVE = {"same"}


@dataclass(frozen=True)
class Problem:
    index: int
    robot: str
    scene: str
    kind: str
    start: Any
    goal: Any = None
    pose: Any = None
    motion: str = "ptp"
    blend: bool = False
    time_limit: float = TIME_LIMIT
    speed_scale: float = 1.0

    @property
    def mode(self) -> str:
        return "lin" if self.motion == "lin" else ("ptp-blend" if self.blend else "ptp-stop")


class Generator:
    """Seeded problems for one robot in one scene."""

    def __init__(self, name: str, robot: Robot, scene: str, world: CollisionWorld, seed: int):
        self.name, self.robot, self.scene, self.world = name, robot, scene, world
        self.lo, self.hi = robot.chain.lower(), robot.chain.upper()
        self.rng = np.random.default_rng(seed)
        # Rough reach: the farthest tool0 of random configurations.
        tips = [robot.kinematics.frame_pose(q, "tool0")[:3, 3] for q in self.uniform(64)]
        self.reach = float(max(np.linalg.norm(t) for t in tips))

    def uniform(self, n: int | None = None) -> Array:
        return self.rng.uniform(self.lo, self.hi, size=None if n is None else (n, len(self.lo)))

    def free(self) -> Array:
        for _ in range(5000):
            q = self.uniform()
            if not self.world.in_collision(q):
                return q
        raise AssertionError(f"no free configuration of {self.name} in {self.scene}")

    def colliding(self) -> Array | None:
        for _ in range(400):
            q = self.uniform()
            if self.world.in_collision(q):
                return q
        return None

    def blocked_pair(self) -> tuple[Array, Array]:
        for _ in range(200):
            a, b = self.free(), self.free()
            if self.world.in_collision_many(edge_configurations(a, b, 0.01)).any():
                return a, b
        return self.free(), self.free()  # (the empty scene rarely blocks a straight segment)

    def tool0(self, q: Array) -> Array:
        return self.robot.kinematics.frame_pose(q, "tool0")

    def problem(self, index: int, kind: str) -> Problem:
        rng = self.rng
        p = Problem(index, self.name, self.scene, kind, None,
                    speed_scale=1.0 if rng.random() < 0.7 else 0.5)
        blend = bool(rng.random() < 0.5)
        if kind == "free-pair":
            return replace(p, start=self.free(), goal=self.free(), blend=blend)
        if kind == "blocked-pair":
            a, b = self.blocked_pair()
            return replace(p, start=a, goal=b, blend=blend)
        if kind == "random-pair":
            return replace(p, start=self.uniform(), goal=self.uniform(), blend=blend)
        if kind == "pose":
            return replace(p, start=self.free(), pose=self.tool0(self.free()), blend=blend)
        if kind == "pose-any":
            return replace(p, start=self.free(), pose=self.tool0(self.uniform()), blend=blend)
        if kind == "lin-short":
            q = self.free()
            t0 = self.tool0(q)
            direction = rng.normal(size=3)
            direction /= np.linalg.norm(direction)
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            rot = t0[:3, :3] @ exp_so3(axis * rng.uniform(0.0, 0.5))
            pose = transform(rot, t0[:3, 3] + direction * rng.uniform(0.05, 0.5))
            return replace(p, start=q, pose=pose, motion="lin")
        if kind == "lin-long":
            return replace(p, start=self.free(), pose=self.tool0(self.free()), motion="lin")
        if kind == "lin-joints":
            return replace(p, start=self.free(), goal=self.free(), motion="lin")
        if kind == "goal-in-collision":
            bad = self.colliding()
            if bad is None:  # a scene where random configurations rarely collide
                return self.problem(index, "out-of-limits")
            if rng.random() < 0.6:
                return replace(p, start=self.free(), goal=bad, blend=blend)
            # The pose of a colliding configuration: another IK branch may be free, so this
            # one is only counted, not required to fail (see MUST_FAIL).
            return replace(p, kind="pose-of-collision", start=self.free(), pose=self.tool0(bad))
        if kind == "unreachable":
            direction = rng.normal(size=3)
            direction[2] = abs(direction[2])
            direction /= np.linalg.norm(direction)
            rot = exp_so3(rng.normal(size=3))
            pose = transform(rot, direction * self.reach * rng.uniform(1.3, 2.0))
            return replace(p, start=self.free(), pose=pose,
                           motion="lin" if rng.random() < 0.4 else "ptp")
        if kind == "out-of-limits":
            goal = self.free()
            j = int(rng.integers(len(goal)))
            beyond = rng.uniform(0.01, 0.5)
            goal[j] = self.hi[j] + beyond if rng.random() < 0.5 else self.lo[j] - beyond
            return replace(p, start=self.free(), goal=goal, blend=blend)
        if kind == "tiny-budget":
            a, b = self.blocked_pair()
            return replace(p, start=a, goal=b, time_limit=1e-4, blend=blend)
        if kind == "same":
            q = self.free()
            which = int(rng.integers(3))
            if which == 0:
                return replace(p, start=q, goal=q.copy(), blend=blend)
            return replace(p, start=q, pose=self.tool0(q), motion="lin" if which == 1 else "ptp")
        if kind == "bad-input":
            q = self.free()
            which = int(rng.integers(5))
            if which == 0:
                return replace(p, start=q, goal=np.append(q, 0.0))
            if which == 1:
                pose = self.tool0(q)
                pose[int(rng.integers(3)), 3] = np.nan
                return replace(p, start=q, pose=pose, motion=("ptp", "lin")[int(rng.integers(2))])
            if which == 2:
                pose = self.tool0(q)
                pose[:3, :3] *= 1.5  # a scaled "rotation"
                return replace(p, start=q, pose=pose, motion=("ptp", "lin")[int(rng.integers(2))])
            if which == 3:
                return replace(p, start=q, pose=self.tool0(q)[:3])  # 3x4
            goal = q.copy()
            goal[0] = np.inf
            return replace(p, start=q, goal=goal)
        raise ValueError(kind)


def schedule(count: int, rng: np.random.Generator, offset: int = 0) -> list[str]:
    """``count`` kinds in proportion to their weights (every kind once when count allows);
    fewer than there are kinds: the next ``count`` kinds in turn from ``offset``."""
    names = list(KINDS)
    if count < len(names):
        return [names[(offset + k) % len(names)] for k in range(count)]
    weights = np.array([KINDS[k] for k in names], float)
    quota = np.floor(weights / weights.sum() * count).astype(int)
    quota = np.maximum(quota, 1 if count >= len(names) else 0)
    kinds = [k for k, n in zip(names, quota, strict=True) for _ in range(n)]
    while len(kinds) < count:
        kinds.append(names[int(rng.choice(len(names), p=weights / weights.sum()))])
    kinds = kinds[:count]
    rng.shuffle(kinds)
    return kinds


@dataclass
class Tally:
    """Counts by category and the problems that broke an invariant."""

    counts: dict[str, dict[str, Counter]]
    violations: list[str]
    untyped: list[str]
    unexpected: list[str]
    slowest: list[tuple[float, str]]
    checks: Counter
    seconds: Counter

    @classmethod
    def new(cls) -> Tally:
        return cls(defaultdict(lambda: defaultdict(Counter)), [], [], [], [], Counter(),
                   Counter())

    def add(self, p: Problem, outcome: str) -> None:
        for axis, key in (("kind", p.kind), ("robot", p.robot), ("scene", p.scene),
                          ("mode", p.mode), ("goal", "pose" if p.pose is not None else "joints"),
                          ("all", "all")):
            self.counts[axis][key]["tried"] += 1
            self.counts[axis][key][outcome] += 1

    def as_json(self, seconds: float) -> dict[str, Any]:
        return {"seconds": round(seconds, 1),
                "counts": {axis: {k: dict(sorted(c.items())) for k, c in sorted(d.items())}
                           for axis, d in self.counts.items()},
                "recheck": dict(self.checks),
                "seconds_by_kind": {k: round(v, 1) for k, v in self.seconds.most_common()},
                "violations": self.violations, "untyped_failures": self.untyped,
                "unexpected_outcomes": self.unexpected,
                "slowest": [[round(s, 3), what] for s, what in sorted(self.slowest)[-10:]]}


def run_problem(robot: Robot, world: CollisionWorld, p: Problem, tally: Tally) -> None:
    options = MotionOptions(motion=p.motion, blend=p.blend, speed_scale=p.speed_scale,
                            ompl=OmplOptions(time_limit=p.time_limit, seed=p.index))
    what = (f"#{p.index} {p.robot}/{p.scene}/{p.kind}/{p.mode}: start {np.round(p.start, 3)}, "
            + (f"goal {np.round(p.goal, 3)}" if p.goal is not None else
               f"pose {np.round(np.asarray(p.pose), 3).tolist()}"))
    begin = time.perf_counter()
    try:
        plan = plan_motion(robot, world, p.start, goal=p.goal, pose=p.pose, options=options)
    except TYPED as exc:
        tally.add(p, type(exc).__name__)
        if p.kind in EXPECTED and not isinstance(exc, EXPECTED[p.kind]):
            tally.unexpected.append(f"{what}: {type(exc).__name__}: {exc}")
        if p.kind in MUST_SOLVE:
            tally.unexpected.append(f"{what}: must be solved, got {type(exc).__name__}: {exc}")
        return
    except Exception as exc:  # anything untyped is a bug
        tally.add(p, "untyped:" + type(exc).__name__)
        tally.untyped.append(f"{what}: {type(exc).__name__}: {exc}")
        return
    finally:
        tally.slowest.append((time.perf_counter() - begin, what))
        tally.slowest[:] = sorted(tally.slowest)[-10:]
        tally.seconds[p.kind] += time.perf_counter() - begin
    tally.add(p, "solved")
    if p.kind in MUST_FAIL:
        tally.unexpected.append(f"{what}: expected a failure, got a plan")
    checked = time.perf_counter()
    line_start = robot.kinematics.frame_pose(p.start, "tool0")[:3, 3]
    result = recheck(robot, world, plan, p.start, line_start)
    tally.checks["dense_replans"] += int(plan.details.get("dense_replans", 0))
    tally.checks["samples_1khz"] += result.samples
    tally.checks["samples_brute_force"] += result.brute_force_samples
    if result.line_deviation_m is not None:
        tally.checks["max_line_deviation_um"] = max(tally.checks["max_line_deviation_um"],
                                                    round(result.line_deviation_m * 1e6))
    if result.final_position_error_m is not None:
        tally.checks["max_final_position_error_um"] = max(
            tally.checks["max_final_position_error_um"],
            round(result.final_position_error_m * 1e6))
    if not result.ok:
        tally.violations.append(f"{what}: " + "; ".join(result.violations))
    tally.seconds["(re-check)"] += time.perf_counter() - checked


def run_suite(robots: dict[str, Robot], per_scene: dict[str, int], seed: int,
              out: Path) -> Tally:
    """``per_scene[robot]`` problems for each robot in each built-in scene."""
    tally = Tally.new()
    begin = time.perf_counter()
    index = 0
    for r, (name, robot) in enumerate(robots.items()):
        for s, scene in enumerate(BUILTIN):
            world = robot.collision_world(load_scene(scene))
            gen = Generator(name, robot, scene, world, seed=seed * 1000 + 10 * r + s)
            for kind in schedule(per_scene[name], gen.rng, index):
                run_problem(robot, world, gen.problem(index, kind), tally)
                index += 1
    report = tally.as_json(time.perf_counter() - begin)
    (out / "invariants.json").write_text(json.dumps(report, indent=1) + "\n")
    _print(report, out / "invariants.json")
    return tally


def _print(report: dict[str, Any], path: Path) -> None:
    print(f"\n{report['counts']['all']['all']['tried']} problems in {report['seconds']} s "
          f"({path})")
    for axis in ("kind", "robot", "scene", "mode", "goal"):
        for key, c in report["counts"][axis].items():
            fails = ", ".join(f"{k} {v}" for k, v in c.items() if k not in ("tried", "solved"))
            print(f"  {axis:<6} {key:<18} tried {c['tried']:>4}  solved {c.get('solved', 0):>4}"
                  f"  {fails}")
    print(f"  re-check: {report['recheck']}")
    print(f"  seconds: {report['seconds_by_kind']}")
    for s, what in report["slowest"][-3:]:
        print(f"  slow: {s} s {what[:100]}")
    for label in ("violations", "untyped_failures", "unexpected_outcomes"):
        print(f"  {label}: {len(report[label])}")


SOLVE_RATE_FLOORS = {"free-pair": 0.93, "pose": 0.95, "blocked-pair": 0.70, "lin-short": 0.48}
"""Least fraction solved per kind of problem in the 1,000-problem run (observed 0.970, 0.993,
0.770, 0.550)."""


def _assert_clean(tally: Tally) -> None:
    problems = ([f"INVARIANT: {v}" for v in tally.violations]
                + [f"UNTYPED: {v}" for v in tally.untyped]
                + [f"UNEXPECTED: {v}" for v in tally.unexpected])
    assert not problems, "\n".join(problems[:20])


def test_thirty_seeded_problems_keep_every_invariant(kr60: Robot, fanuc: Robot,
                                                     tmp_path: Path) -> None:
    tally = run_suite({"KR60": kr60, "Fanuc": fanuc}, {"KR60": 6, "Fanuc": 2}, seed=1,
                      out=tmp_path)
    _assert_clean(tally)
    assert tally.counts["all"]["all"]["solved"] >= 8


@pytest.mark.slow
def test_a_thousand_seeded_problems_keep_every_invariant(kr60: Robot, fanuc: Robot,
                                                         tmp_path: Path) -> None:
    tally = run_suite({"KR60": kr60, "Fanuc": fanuc}, {"KR60": 200, "Fanuc": 50}, seed=2,
                      out=tmp_path)
    _assert_clean(tally)
    every = tally.counts["all"]["all"]
    assert every["tried"] >= 1000
    # Observed (seed 2, the run before these floors): 635 / 1,000 solved; free-pair 197/203,
    # pose 150/151, blocked-pair 77/100, lin-short 82/149. Floors a little below those rates.
    assert every["solved"] / every["tried"] >= 0.60
    for kind, floor in SOLVE_RATE_FLOORS.items():
        c = tally.counts["kind"][kind]
        assert c["tried"] >= 50, f"{kind}: only {c['tried']} tried"
        rate = c.get("solved", 0) / c["tried"]
        assert rate >= floor, f"{kind}: solved {c.get('solved', 0)}/{c['tried']} < {floor:.0%}"
    for name in ("StartInCollisionError", "GoalInCollisionError", "OutOfLimitsError",
                 "NoPathError", "LinBlockedError", "InvalidInputError"):
        assert every[name] > 0, f"no {name}: that failure path was not exercised"
    assert sum(v for k, v in every.items() if k in ("UnreachableError", "JointLimitError",
                                                     "AllSolutionsInCollisionError")) > 0


def test_the_finite_difference_check_sees_a_limit_exceeded_by_one_percent() -> None:
    t = np.arange(0.0, 1.0, 1e-3)
    ones = np.ones(1)
    lim = {"lower": -10 * ones, "upper": 10 * ones, "vmax": ones, "amax": 10 * ones,
           "jmax": 100 * ones}
    ok = (0.99 * t)[:, None]        # 0.99 rad/s: within the 1 rad/s limit
    fast = (1.01 * t)[:, None]      # 1.01 rad/s: over it
    assert finite_difference_violations(t, ok, **lim) == []
    assert any("velocity" in v for v in finite_difference_violations(t, fast, **lim))
    jerky = (0.5 * 10.5 * t ** 2)[:, None]  # 10.5 rad/s^2: over the acceleration limit
    assert any("acceleration" in v for v in finite_difference_violations(t, jerky, **lim))
