"""The planning sections of the benchmark report (``bench/report.py``): motion planning (the
problems whose straight line is blocked, the free-line ones apart, the cost against obstacles and
joints, the profile), time-parameterisation and the OMPL planners' ranking."""

from __future__ import annotations

from typing import Any

import numpy as np
from report_format import HEAD, NOTES, PUBLISHED, fmt_pct, fmt_s, fmt_x, solver_rows, table

PLAN_BEFORE = ("Before this work (issue 11's profile of the landed code, 20 KR60 plans in "
               "`table`): 54 ms per plan, about two thirds in `CollisionWorld._many` (numpy "
               "broadphase, then python-fcl with one `fcl.Transform` per link per "
               "configuration) and 12 ms in sampling the timed trajectory one `at()` call at a "
               "time. At the start of the compiled-walk rework: 6.3 ms median per KR60 plan, "
               "78 % of it in the edge walk at 2.6 us per configuration.")


def _profile_section(profile: dict[str, Any]) -> list[str]:
    """Where a KR60 plan's time goes (plan_profile.py), with the figures before the work."""
    stages = profile.get("stages_s")
    if not stages:
        return [f"Profile not measured: {profile.get('error', 'not run')[:300]}", ""]
    total = sum(stages.values())
    rows = [[name, fmt_s(sec), f"{100 * sec / total:.0f} %"] for name, sec in stages.items()]
    return ["### Where a KR60 plan's time goes", "",
            f"{profile['problems']} problems whose straight line is blocked, one untimed pass "
            "with the collision world's entry points wrapped in timers "
            f"({fmt_s(profile['seconds_per_plan'])} per plan with the wrappers).", "",
            *table(["stage", "per plan", "share"], rows), PLAN_BEFORE, ""]


def _slopes(doc: dict[str, Any]) -> list[str]:
    """Fitted cost curves: time ~ a * obstacles^b (least squares in log-log) and the extra time
    per obstacle; per solver, over the obstacle counts where it has a median."""
    lines = []
    series: dict[str, list[tuple[int, float]]] = {}
    for name, case in doc["cases"].items():
        if not name.startswith("boxes_"):
            continue
        for solver, s in case["solvers"].items():
            med = ((s.get("summary") or {}).get("time_all_s") or {}).get("median")
            if med:
                series.setdefault(solver, []).append((int(case["obstacles"]), float(med)))
    for solver, points in series.items():
        if len(points) < 2:
            continue
        x = np.log([p[0] for p in points])
        y = np.log([p[1] for p in points])
        b, _ = np.polyfit(x, y, 1)
        (n0, t0), (n1, t1) = min(points), max(points)
        lines.append(f"{solver}: time ~ obstacles^{b:.2f} (log-log fit over {len(points)} "
                     f"counts); {fmt_s((t1 - t0) / (n1 - n0))} more per obstacle from {n0} to "
                     f"{n1}")
    joints = {case["dof"]: ((case["solvers"].get("usar-arm", {}).get("summary") or {})
                            .get("time_all_s") or {}).get("median")
              for name, case in doc["cases"].items() if not name.startswith("boxes_")}
    if all(joints.get(d) for d in (6, 7)):
        lines.append(f"usar-arm against joints (same scenes): {fmt_s(joints[6])} at 6, "
                     f"{fmt_s(joints[7])} at 7 joints ({joints[7] / joints[6]:.2f}x per added "
                     "joint, two robots: a slope, not a curve)")
    return (["Fitted slopes: " + "; ".join(lines) + ".", ""] if lines else [])


def plan_section(doc: dict[str, Any]) -> list[str]:
    def fn(_: str, s: dict[str, Any]) -> str:
        sm = s["summary"]
        return f"{sm.get('paths_in_collision', 0)} / {fmt_s(sm['duration_s']['median'])}"

    out = ["On the problems whose straight start-goal line is blocked (a planner must plan); "
           "every target and slope is taken on them. The problems whose straight line is free "
           "(usar-arm returns it before any planner runs) are reported apart, below.", ""]
    for name, case in doc["cases"].items():
        if name.startswith("boxes_"):
            continue
        scenes = ", ".join(case["scenes"])
        out += [f"### {case['robot']} ({case['dof']} joints), {case['problems']['count']} "
                f"start/goal pairs over {scenes}, straight line blocked", "",
                *table([*HEAD, "paths in collision / median duration", NOTES],
                       solver_rows("plan", case, fn))]
        ours = case["solvers"]["usar-arm"].get("summary", {}).get("by_scene", {})
        if ours:
            out += ["usar-arm per scene: " + "; ".join(
                f"{sc} {v['verified']}/{v['problems']}, median "
                f"{fmt_s(v['time_all_s']['median'])}" for sc, v in ours.items()), ""]
    out += ["### Cost against the number of obstacles (KR60, same start/goal pairs)", ""]
    rows = []
    names = None
    for name, case in doc["cases"].items():
        if not name.startswith("boxes_"):
            continue
        names = names or list(case["solvers"])
        cells = [str(case["obstacles"])]
        for n in names:
            sm = case["solvers"][n].get("summary") or {}
            med = (sm.get("time_all_s") or {}).get("median")
            cells.append("-" if med is None else
                         f"{fmt_s(med)} ({sm.get('verified')}/{sm.get('problems')})")
        rows.append(cells)
    if names:
        out += table(["boxes", *[f"{n} median (verified)" for n in names]], rows)
        out += _slopes(doc)
    out += _free_line(doc.get("free_line") or {}, fn)
    out += _profile_section(doc.get("profile") or {})
    out += ["![Planning time](plan.png)", "",
            "![Cost against obstacles](scaling_obstacles.png)", "",
            "![Cost against joints](scaling_joints.png)", ""]
    return out


def _timing_case(case: dict[str, Any]) -> list[list[str]]:
    rows = []
    for name, s in case["solvers"].items():
        if "skipped" in s:
            rows.append([name, f"skipped: {s['skipped']}", "-", "-", "-", "-", ""])
            continue
        sm = s["summary"]
        r = sm["ratio_to_toppra"]
        ours = [n for n, x in case["solvers"].items() if x["kind"] == "ours"]
        rat = case["ratios"].get(name, {})
        computation = f"{fmt_s(sm['time_all_s']['median'])} / {fmt_s(sm['time_all_s']['mean'])}"
        if s["kind"] == "peer":
            computation += " (usar-arm / peer: " + ", ".join(
                f"{o} {fmt_x(rat.get(o, {}).get('median'))}" for o in ours) + ")"
        rows.append([f"{name} {s.get('version', '')}".strip(),
                     f"{fmt_pct(sm['success_rate'])} ({sm['verified']}/{sm['problems']})",
                     computation,
                     fmt_s(sm["duration_s"]["median"]),
                     f"{fmt_x(r['median'])} / {fmt_x(r['p90'])}",
                     f"{sm.get('in_collision', 0)} / {sm.get('over_limits', 0)}",
                     PUBLISHED.get(("timing", name), "") if s["kind"] == "peer"
                     else s["note"]])
    return rows


TIMING_TITLES = {"KR60": "paths from our planner (the scene's obstacles count)",
                 "KR60 neutral": "random polylines in the empty scene (nothing to hit)"}


def timing_section(doc: dict[str, Any]) -> list[str]:
    out = []
    for name, case in doc["cases"].items():
        out += [f"### {name}: {case['problems']['count']} "
                f"{TIMING_TITLES.get(name, case.get('source', ''))}, full limits", "",
                *table(["solver", "verified", "computation with its 100 Hz samples, median / "
                        "mean", "duration median",
                        "duration / toppra (median / p90)",
                        "trajectories in collision / over limits", "notes"],
                       _timing_case(case))]
    rule = doc.get("settings", {}).get("rule")
    return [*out, *([f"The rule: {rule}", ""] if rule else []),
            "![Time-parameterisation](timing.png)", ""]


def _free_line(cases: dict[str, Any], fn: Any) -> list[str]:
    """The problems whose straight line is free, apart: no target or slope counts them."""
    if not cases:
        return ["### Problems whose straight line is free", "", "None in this run.", ""]
    out = ["### Problems whose straight line is free (reported apart: usar-arm returns the "
           "line before any planner runs; no target or slope counts them)", ""]
    for name, case in cases.items():
        out += [f"{name}: {case['problems']['count']} problems over "
                f"{', '.join(case['scenes'])}", "",
                *table([*HEAD, "paths in collision / median duration", NOTES],
                       solver_rows("plan", case, fn))]
    return out


def planners_section(doc: dict[str, Any]) -> list[str]:
    """The planners of ompl_planning.yaml, ranked (bench/planners.py)."""
    rows = [[str(k + 1), r["planner"], r["ompl"],
             f"{fmt_pct(r['success_rate'])} ({r['verified']}/{r['problems']})",
             fmt_s(r["median_s"]), fmt_s(r["p90_s"]), str(r["over_budget"]),
             str(r["paths_in_collision"])] for k, r in enumerate(doc["ranking"])]
    settings = doc["settings"]
    rule = settings.get("ranking_rule", "ranked by verified success, then median time")
    free = (doc.get("free_line") or {}).get("KR60")
    free_row = []
    if free:
        sums = [s.get("summary") or {} for s in free["solvers"].values()]
        medians = [(sm.get("time_all_s") or {}).get("median") for sm in sums]
        medians = [m for m in medians if m is not None]
        free_row = [f"Free-line problems, reported apart ({free['problems']['count']}: "
                    "plan_to_joints returns the straight line before any planner runs): "
                    f"verified {min(sm.get('verified', 0) for sm in sums)}-"
                    f"{max(sm.get('verified', 0) for sm in sums)} by each planner, medians "
                    + (f"{fmt_s(min(medians))}-{fmt_s(max(medians))}." if medians else "-."),
                    ""]
    return ["Every OMPL planner the MoveIt package's `ompl_planning.yaml` offers, each through "
            "usar-arm's own OMPL adapter (`plan_to_joints`, "
            f"{settings['time_limit_s']:g} s budget), on {settings['problems']} (KR60). "
            f"{rule} The YAML lists them in this order, the first as its default. The "
            "optimising planners (RRTstar, PRMstar) refine their path until the budget ends, "
            "by design: over budget counts calls that ended after it.",
            "", *table(["rank", "planner (MoveIt)", "OMPL class", "verified", "median", "p90",
                        "over budget", "paths in collision"], rows), *free_row]


def carry_section(doc: dict[str, Any]) -> list[str]:
    """Planning with an attached part against the bare arm, on the same problems."""
    out = ["The planning stage's KR60 `table` problems, planned bare and carrying the table's "
           "part (a box under the tool, the gripper allowed to touch it); each path judged by "
           "the independent judge with what that solver carried (the judge places the part "
           "itself from its shape, link and grasp).", ""]
    for name, case in doc["cases"].items():
        out += [f"### {name}: {case['problems']['count']} start/goal pairs "
                f"({case.get('left_out', 0)} left out: the carried part collides at their "
                "start or goal)", "",
                *table([*HEAD, NOTES], solver_rows("carry", case))]
        for label, c in (case.get("cost") or {}).items():
            out.append(f"* carrying / bare, {label.replace('_', ' ')} ({c['problems']} "
                       f"problems): ratio of the medians {fmt_x(c['median_ratio'])}, median of "
                       f"the per-problem ratios {fmt_x(c['per_problem_median'])}")
        out.append("")
    return out
