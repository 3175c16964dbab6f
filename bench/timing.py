"""Time-parameterisation stage: the same geometric paths (our planner's, fixed in the problem
file) timed under the same velocity and acceleration limits by usar-arm (Ruckig, jerk-limited:
``stop`` at every waypoint, the default, and ``blend``), TOPP-RA (toppra: time-optimal on a cubic
spline through the waypoints, no jerk limit) and roboplan (its TOPP-RA, Hermite spline stopping
at every waypoint).

As a solver (our side)::

    python bench/timing.py --mode stop|blend PROBLEMS.json RESULTS.json

Timed: ``control.timing.stop_at_waypoints`` / ``blended`` (blend re-checks its segments for
collisions in the problem's scene and falls back to stopping where a segment fails) and the
trajectory's 100 Hz samples (``evaluate``): roboplan's ``generate`` samples at 100 Hz inside
its own call, which cannot be taken apart, so every solver's time includes its 100 Hz sampling
(``timing_seconds``: ours and toppra's without it). ``seconds_with_1khz_samples``: the timing
again, plus every 1 ms sample of it (the 1 kHz target). Figures: duration (s) and its ratio to
toppra's on the same path; computation time per trajectory (s). Every trajectory's 100 Hz
samples are checked: ends at the waypoints, velocity and acceleration within the limits (finite
differences), collision-free in the scene (the judge) - toppra's spline may leave the
collision-checked polyline.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

import common
import numpy as np
import verify
from common import Context, peerio
from scenes import from_json

from usar_arm.control.timing import DEFAULT_RATE_HZ, blended, stop_at_waypoints
from usar_arm.control.trajectory import MotionLimits
from usar_arm.planning.robot import robot_from_files


def solver_main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mode", choices=("stop", "blend"), default="stop")
    ap.add_argument("problems")
    ap.add_argument("results")
    a = ap.parse_args(argv)
    spec = common.read_json(common.Path(a.problems))
    names = tuple(spec["joint_names"])
    limits = MotionLimits(*(np.array(spec[k], float)
                            for k in ("lower", "upper", "vmax", "amax", "jmax")))
    robot = robot_from_files(spec["urdf"], spec["srdf"])
    worlds: dict[str, Any] = {}

    def solve(p: dict[str, Any]) -> dict[str, Any]:
        wp = peerio.waypoints(p, len(names))
        sampled_1khz = None
        if a.mode == "stop":
            motion, sec = peerio.timed(stop_at_waypoints, names, wp, limits)
            begin = time.perf_counter()  # timing again, plus every 1 ms sample of it
            again = stop_at_waypoints(names, wp, limits)
            again.evaluate(np.arange(0.0, again.duration, 1e-3))
            sampled_1khz = time.perf_counter() - begin
        else:
            if p["scene"] not in worlds:
                worlds[p["scene"]] = robot.collision_world(
                    from_json(p["scene"], spec["scenes"][p["scene"]]))
            motion, sec = peerio.timed(blended, names, wp, limits,
                                       worlds[p["scene"]].in_collision_many,
                                       1.0 / DEFAULT_RATE_HZ)
        begin = time.perf_counter()  # the 100 Hz samples, as roboplan's timed call makes them
        t = peerio.sample_times(motion.duration)
        q = motion.evaluate(t)[0]
        sampling = time.perf_counter() - begin
        return {"success": True, "seconds": sec + sampling, "timing_seconds": sec,
                "duration_s": motion.duration, "fallbacks": motion.fallbacks,
                "samples": {"t": t, "q": q}, "seconds_with_1khz_samples": sampled_1khz}

    peerio.write(a.results, peer=f"usar-arm ({a.mode})", dist="usar-arm", stage="topp",
                 results=peerio.solve_all(spec["problems"], solve),
                 settings={"mode": a.mode, "jerk_limits": spec["jmax"],
                           "blend_check_step_s": 1.0 / DEFAULT_RATE_HZ},
                 notes="seconds = the timing + its 100 Hz samples (as roboplan's generate); "
                       "timing_seconds = the timing alone")
    return 0


# ------------------------------------------------------------------------------ the stage
CASES = (("KR60", "topp_KR60"), ("KR60 neutral", "topp_KR60_neutral"))
"""Our planner's polylines (a spline that leaves one may hit what the polyline avoids: the judge
counts that as a failure), and random polylines in the empty scene (nothing to hit: durations
compare on equal terms)."""


def run(ctx: Context) -> dict[str, Any]:
    """Run both timing cases and return the stage document."""
    started = time.perf_counter()
    cases = {name: _case(ctx, key) for name, key in CASES}
    return common.stage_document("timing", ctx.mode, {"rounds": ctx.rounds, "speed_scale": 1.0,
                                                      "rule": RULE},
                                 cases, _targets(cases["KR60"], cases["KR60 neutral"]), started)


RULE = ("Every solver times the same polylines; every solver's computation time includes its "
        "100 Hz sampling of the trajectory (roboplan samples inside its timed call, which "
        "cannot be taken apart: usar-arm and toppra sample in theirs too). A trajectory passes "
        "when it starts and ends at the polyline's ends, stays within the velocity and "
        "acceleration limits (finite differences of its 100 Hz samples) and, sampled at 100 Hz,"
        " is collision-free by the judge in the problem's scene. A spline through the waypoints"
        " (toppra) may leave the polyline the planner checked: on the planner's paths that can "
        "fail it; on the neutral set (empty scene) it cannot.")


def _case(ctx: Context, key: str) -> dict[str, Any]:
    path, spec = ctx.problem(key)
    solvers = [common.ours("usar-arm", "timing.py", "--mode", "stop",
                           note="stop_at_waypoints (default): Ruckig, jerk-limited"),
               common.ours("usar-arm blend", "timing.py", "--mode", "blend",
                           note="blended: Ruckig pass-through, collision re-check"),
               ctx.peer("toppra", "topp", "TOPP-RA on a cubic spline (time-optimal, no jerk)"),
               ctx.peer("roboplan", "topp", "TOPP-RA, Hermite spline (stops at waypoints)")]
    outcomes = common.run_alternating(spec, solvers, ctx.work, ctx.rounds, key)
    judges = {n: verify.Judge.for_scene(spec, n) for n in spec["scenes"]}
    vmax, amax = np.array(spec["vmax"]), np.array(spec["amax"])
    reference = {r["id"]: r.get("duration_s") for r in outcomes["toppra"].results
                 if r.get("success")}

    def check(p: dict[str, Any], r: dict[str, Any]) -> dict[str, Any]:
        ref = reference.get(p["id"])
        row: dict[str, Any] = {"duration_s": r.get("duration_s"),
                               "timing_seconds": r.get("timing_seconds"),
                               "seconds_with_1khz_samples": r.get("seconds_with_1khz_samples"),
                               "waypoints": len(p["waypoints"]),
                               "ratio_to_toppra": common.ratio(r.get("duration_s"), ref)}
        samples = r.get("samples") if r.get("success") else None
        if not samples:
            return {**row, "verified": False}
        c = verify.check_trajectory(judges[p["scene"]], np.array(p["waypoints"]),
                                    np.array(samples["t"]), np.array(samples["q"]), vmax, amax)
        return {**row, "verified": c.verified, "ends_match": c.ends_match,
                "max_velocity_ratio": c.max_velocity_ratio,
                "max_acceleration_ratio": c.max_acceleration_ratio,
                "collision_free": c.collision_free, "fallbacks": r.get("fallbacks")}

    def extra(raw: dict[str, list[Any]]) -> dict[str, Any]:
        near_5s = [sec for sec, d in zip(raw["seconds_with_1khz_samples"], raw["duration_s"],
                                         strict=True) if sec is not None and d and 4 <= d <= 6]
        return {"duration_s": common.stats(raw["duration_s"]),
                "timing_seconds": common.stats(raw["timing_seconds"]),
                "timing_and_1khz_samples_4_to_6_s": common.stats(near_5s),
                "ratio_to_toppra": common.stats(raw["ratio_to_toppra"]),
                "in_collision": sum(1 for c in raw.get("collision_free", []) if c is False),
                "over_limits": sum(1 for v, a in zip(raw.get("max_velocity_ratio", []),
                                                     raw.get("max_acceleration_ratio", []),
                                                     strict=True)
                                   if v is not None and (v > verify.VELOCITY_SLACK
                                                         or a > verify.ACCELERATION_SLACK))}

    return {"robot": spec["robot"], "source": spec.get("source", ""),
            **common.build_case(path, spec, outcomes, check, extra)}


def _ms(seconds: float | None) -> str:
    return "-" if seconds is None else f"{seconds * 1e3:.3g} ms"


def _targets(case: dict[str, Any], neutral: dict[str, Any]) -> list[dict[str, Any]]:
    def s(name: str, c: dict[str, Any] = case) -> dict[str, Any]:
        return c["solvers"][name].get("summary") or {}

    stop, blend = s("usar-arm"), s("usar-arm blend")
    neutral_blend = s("usar-arm blend", neutral)
    return [
        common.target("Timing, neutral paths: blend duration / TOPP-RA (toppra) duration, "
                      "median", (neutral_blend.get("ratio_to_toppra") or {}).get("median"),
                      1.25, "<=", "ratio", "random polylines in the empty scene"),
        common.target("Timing: blend duration / TOPP-RA (toppra) duration, median",
                      (blend.get("ratio_to_toppra") or {}).get("median"), 1.25, "<=", "ratio"),
        common.target("Timing: Ruckig computation per trajectory (stop, default), mean, "
                      "without the 100 Hz samples", (stop.get("timing_seconds") or {}).get(
                          "mean"), 1e-3, "<=", "s", "with them (as the peers are timed): "
                      f"{_ms((stop.get('time_all_s') or {}).get('mean'))}"),
        *[common.target(f"Timing (stop) plus sampling at 1 kHz, trajectories of 4-6 s, median"
                        f" ({label})", (s("usar-arm", c).get("timing_and_1khz_samples_4_to_6_s")
                                        or {}).get("median"), 1e-3, "<=", "s")
          for label, c in (("the planner's paths", case), ("neutral paths", neutral))],
        common.target("Timing: stop trajectories verified (limits, ends, collision-free)",
                      stop.get("success_rate"), 1.0, ">=", "fraction"),
    ]


if __name__ == "__main__":
    sys.exit(solver_main())
