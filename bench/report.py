"""The benchmark report: ``<results>/README.md`` (tables, pass/fail against the targets) and PNG
plots, generated from the ``<results>/<stage>.json`` files.

    python bench/report.py [bench/results]

Times in the tables are per problem over every problem attempted (a failure costs its time);
"verified" counts only answers that passed the harness's own checks. Ratios are usar-arm's
median time / the peer's median time, measured in the same run on the same problems.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

import common
import numpy as np
import plots

STAGE_TITLES = {"ik": "Inverse kinematics", "collision": "Collision checking",
                "plan": "Motion planning", "timing": "Time-parameterisation",
                "discovery": "Discovery + URDF", "execution": "Execution (embedded simulator)",
                "calibrate": "Calibration on the wire",
                "workspace": "Workspace: reachability maps and base placement",
                "planners": "OMPL planners for the MoveIt package"}
PUBLISHED = {
    ("ik", "pytracik"): "99.35 %, 0.92 ms mean (docs/peers.md, 2,000 poses); TRAC-IK README: "
                        "99.56-100 %, 0.18-0.46 ms",
    ("ik", "mplib"): "100 %, 7.2 ms (docs/peers.md)",
    ("ik", "roboplan"): "90 %, 0.29 ms (docs/peers.md)",
    ("ik", "opw"): "100 %, 15 us with exact OPW parameters (docs/peers.md)",
    ("ik", "ikpy"): "84 %, 12 ms (docs/peers.md)",
    ("collision", "roboplan"): "coal default requests miss ~27 % of cylinder overlaps "
                               "(docs/peers.md)",
    ("plan", "mplib"): "plan_qpos median 44 ms, one easy query (docs/peers.md)",
    ("plan", "roboplan"): "RRT-Connect 0.7 ms, one easy query (docs/peers.md)",
    ("timing", "toppra"): "20-24 ms per path (docs/peers.md)",
    ("timing", "roboplan"): "0.55 ms (docs/peers.md)",
}


def fmt_s(x: float | None) -> str:
    """A duration in the unit that reads best (s, ms, us)."""
    if x is None:
        return "-"
    if x >= 1.0:
        return f"{x:.2f} s"
    if x >= 1e-3:
        return f"{x * 1e3:.3g} ms"
    return f"{x * 1e6:.3g} us"


def fmt_pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.2f} %"


def fmt_x(x: float | None) -> str:
    return "-" if x is None else f"{x:.3g}x"


def fmt_measured(t: dict[str, Any]) -> str:
    m, unit = t["measured"], t["unit"]
    if m is None:
        return "-"
    if unit == "s":
        return fmt_s(m)
    if unit == "fraction":
        return fmt_pct(m)
    if unit == "ratio":
        return fmt_x(m)
    if unit == "m":
        return f"{m * 1e3:.3g} mm"
    if unit == "rad":
        return f"{m * 1e3:.3g} mrad"
    return f"{m:.4g} {unit}"


def fmt_threshold(t: dict[str, Any]) -> str:
    fake = {**t, "measured": t["threshold"]}
    return f"{t['better']} {fmt_measured(fake)}"


def _row(cells: list[str]) -> str:
    return "| " + " | ".join(c.replace("|", "/") for c in cells) + " |"


def table(head: list[str], rows: list[list[str]]) -> list[str]:
    return [_row(head), _row(["---"] * len(head)), *(_row(r) for r in rows), ""]


# ------------------------------------------------------------------------------ sections
def targets_section(docs: dict[str, dict[str, Any]]) -> list[str]:
    rows = []
    for stage, doc in docs.items():
        for t in doc.get("targets", []):
            rows.append([STAGE_TITLES[stage], t["target"], fmt_measured(t), fmt_threshold(t),
                         "PASS" if t["pass"] else "**FAIL**", t.get("note", "")])
    return ["## Targets", "", *table(["stage", "target", "measured", "target", "result",
                                      "note"], rows)]


def solver_rows(stage: str, case: dict[str, Any], extra: Any = None) -> list[list[str]]:
    """One row per solver: verified success, time median/p90/mean, our/peer ratios."""
    rows = []
    ours = [n for n, s in case["solvers"].items() if s["kind"] == "ours"]
    for name, s in case["solvers"].items():
        if "skipped" in s:
            rows.append([name, f"skipped: {s['skipped']}", *["-"] * 5, ""])
            continue
        sm = s["summary"]
        t = sm["time_all_s"]
        if s["kind"] == "peer":
            r = case["ratios"].get(name, {})
            count = case["problems"]["count"]
            ratio = " / ".join(
                f"{o}: {fmt_x(r.get(o, {}).get('median'))}"
                + (f" (over {r[o]['problems']})" if r.get(o, {}).get("problems", count) != count
                   else "") for o in ours)
        else:
            ratio = "-"
        wrong = sm.get("answered_but_wrong")
        ok = f"{fmt_pct(sm['success_rate'])} ({sm['verified']}/{sm['problems']})"
        if wrong:
            why = [f"{sm[k]} {label}" for k, label in (
                ("paths_in_collision", "in collision"),
                ("ends_off_by_whole_turns", "ending 2 pi off"),
                ("answered_after_budget", "after the 2 s budget")) if sm.get(k)]
            ok += f", {wrong} answered but wrong" + (f" ({', '.join(why)})" if why else "")
        cells = [f"{name} {s.get('version', '')}".strip(), ok, fmt_s(t["median"]),
                 fmt_s(t["p90"]), fmt_s(t["mean"]), ratio]
        if extra is not None:
            cells.append(extra(name, s))
        published = PUBLISHED.get((stage, name), "")
        cells.append(f"{s['note']}; published/earlier: {published}" if published else s["note"])
        rows.append(cells)
    return rows


HEAD = ["solver", "verified success", "median", "p90", "mean", "usar-arm / peer (median)"]
NOTES = "what is timed; published or earlier figures"


def ik_section(doc: dict[str, Any]) -> list[str]:
    out = []
    for name, case in doc["cases"].items():
        tol = case["tolerance"]
        out += [f"### {name} ({case['dof']} joints), {case['problems']['count']} poses", "",
                f"Tolerance {tol['position_m']:g} m, {tol['orientation_rad']:g} rad; seed = "
                "mid-range of the limits; success = Pinocchio FK of the answer within the "
                "tolerance and the limits.", "",
                *table([*HEAD, NOTES], solver_rows("ik", case))]
    out += ["![IK time per pose](ik.png)", ""]
    return out


def collision_section(doc: dict[str, Any]) -> list[str]:
    def fn(_: str, s: dict[str, Any]) -> str:
        sm = s["summary"]
        return f"{sm.get('false_negatives', 0)} / {sm.get('false_positives', 0)}"

    out = []
    for name, case in doc["cases"].items():
        if name != "table":
            continue
        frac = case["solvers"]["usar-arm"]["summary"].get("colliding_fraction")
        out += [f"### KR60 in `table` ({case['obstacles']} obstacles), "
                f"{case['problems']['count']} random configurations "
                f"({fmt_pct(frac)} in collision)", "",
                *table([*HEAD, "missed / invented contacts", NOTES],
                       solver_rows("collision", case, fn))]
    worst: dict[str, dict[str, float]] = {}
    for c in doc["cases"].values():
        for n, s in c["solvers"].items():
            sm = s.get("summary") or {}
            for key in ("fk_max_error_m", "fk_max_error_rad"):
                if sm.get(key) is not None:
                    worst.setdefault(n, {})[key] = max(worst.get(n, {}).get(key, 0.0), sm[key])
    if worst:
        out += ["FK of tool0 at the same configurations against the judge's (Pinocchio on the "
                "same URDF), largest difference over every scene: " + ", ".join(
                    f"{n} {e['fk_max_error_m']:.2g} m" + (
                        f" and {e['fk_max_error_rad']:.2g} rad" if "fk_max_error_rad" in e
                        else " (rotation not measured in this run)")
                    for n, e in worst.items() if "fk_max_error_m" in e) + ".", ""]
    out += ["### Cost against the number of obstacles (KR60, boxes of 0.1 m), mean per "
            "configuration", ""]
    names = list(next(iter(doc["cases"].values()))["solvers"])
    rows = []
    for name, case in doc["cases"].items():
        if not name.startswith("boxes_"):
            continue
        cells = [str(case["obstacles"])]
        for n in names:
            s = case["solvers"][n]
            sm = s.get("summary") or {}
            ok = sm.get("success_rate")
            mean = (sm.get("time_all_s") or {}).get("mean")
            cells.append("-" if mean is None else f"{fmt_s(mean)} ({fmt_pct(ok)} agree)")
        rows.append(cells)
    out += table(["boxes", *names], rows)
    out += ["![Collision check time](collision.png)", "",
            "![Cost against obstacles](scaling_obstacles.png)", ""]
    return out


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
            f"{profile['problems']} problems, one untimed pass with the collision world's entry "
            f"points wrapped in timers ({fmt_s(profile['seconds_per_plan'])} per plan with the "
            "wrappers).", "", *table(["stage", "per plan", "share"], rows), PLAN_BEFORE, ""]


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

    out = []
    for name, case in doc["cases"].items():
        if name.startswith("boxes_"):
            continue
        scenes = ", ".join(case["scenes"])
        out += [f"### {case['robot']} ({case['dof']} joints), {case['problems']['count']} "
                f"start/goal pairs over {scenes}", "",
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
                *table(["solver", "verified", "computation median / mean", "duration median",
                        "duration / toppra (median / p90)",
                        "trajectories in collision / over limits", "notes"],
                       _timing_case(case))]
    rule = doc.get("settings", {}).get("rule")
    return [*out, *([f"The rule: {rule}", ""] if rule else []),
            "![Time-parameterisation](timing.png)", ""]


def describe_section(doc: dict[str, Any]) -> list[str]:
    rows = []
    for name, case in doc["cases"].items():
        s = case["solvers"]["usar-arm"]
        sm = s.get("summary") or {}
        acc = sm.get("accuracy") or {}
        rows.append([name, str(sm.get("problems")), fmt_s((sm.get("time_all_s") or {})
                                                           .get("median")),
                     fmt_s((sm.get("discovery_seconds") or {}).get("median")),
                     fmt_s((sm.get("build_seconds") or {}).get("median")),
                     f"{1e3 * acc.get('max_flange_error_m', float('nan')):.3g} mm",
                     f"{1e3 * acc.get('max_joint_origin_error_m', float('nan')):.3g} mm",
                     f"{1e3 * acc.get('max_joint_axis_error_rad', float('nan')):.3g} mrad",
                     f"{acc.get('configurations', '-')}"])
    return ["No peer learns an arm over the USARSim wire; our figures only. Accuracy: the "
            "description's forward kinematics against the simulator's own model at seeded "
            "random configurations (max over them).", "",
            *table(["robot (wire)", "runs", "total median", "discovery (TCP)",
                    "build + checks + ACM", "max flange error", "max joint-origin error",
                    "max joint-axis error", "configurations"], rows),
            "![Discovery](discovery.png)", ""]


def execution_section(doc: dict[str, Any]) -> list[str]:
    out = []
    for name, case in doc["cases"].items():
        s = case["solvers"]["usar-arm"]
        raw = s.get("raw") or {}
        sm = s.get("summary") or {}
        out += [f"### {name}: {sm.get('moves')} moves, cycle {fmt_s(sm.get('cycle_seconds'))}",
                ""]
        if sm.get("error"):
            out += [f"Failed: {sm['error']}", ""]
        rows = []
        for k in range(len(raw.get("move", []))):
            def g(key: str, scale: float = 1.0, fmt: str = ".3g", k: int = k,
                  raw: dict[str, Any] = raw) -> str:
                v = raw.get(key, [None] * (k + 1))[k]
                return "-" if v is None else f"{v * scale:{fmt}}"

            rows.append([raw["move"][k], raw["motion"][k], g("planning_s", 1e3),
                         g("duration_s"), g("max_tracking_error_rad", 1e3),
                         g("rate_hz", 1, ".2f"), g("jitter_p99_ms"),
                         f"{g('true_tip_error_m', 1e3)} / {g('true_tip_error_rad', 1e3)}",
                         f"{g('tip_error_m', 1e3)} / {g('tip_error_rad', 1e3)}",
                         f"{g('tip_error_before_correction_m', 1e3)} / "
                         f"{g('tip_error_before_correction_rad', 1e3)}"])
        out += table(["move", "type", "planning ms", "duration s", "max tracking mrad",
                      "rate Hz", "jitter p99 ms", "tool0 error mm / mrad (physics)",
                      "(tip sensor estimate)", "(before correction)"], rows)
    out += ["![Execution](execution.png)", ""]
    return out


def calibrate_section(doc: dict[str, Any]) -> list[str]:
    rows = []
    for name, case in doc["cases"].items():
        sm = case["solvers"]["usar-arm"].get("summary") or {}
        milli = ["-" if sm.get(k) is None else f"{sm[k] * 1e3:.3f}"
                 for k in ("learnt_m", "learnt_rad", "calibrated_m", "calibrated_rad")]
        rows.append([name, *milli, str(sm.get("readings") or "-"),
                     fmt_s(sm.get("calibration_seconds")), fmt_s(sm.get("seconds")),
                     (sm.get("error") or "")[:90]])
    return ["No peer calibrates an arm; our figures only. Each row is `usar-arm urdf` on the "
            "embedded simulator (default UDK wire, --speed 1): discovery, a calibration tour "
            "through the poses reading the tip sensor, the fit, the files. Judged: tool0 of the "
            "URDF (the judge's own Pinocchio model) against the simulator's own geometry at "
            f"{doc['settings'].get('configurations')} seeded configurations (max).", "",
            *table(["robot (tour)", "as learnt mm", "as learnt mrad", "calibrated mm",
                    "calibrated mrad", "readings", "calibration", "urdf in all", "note"],
                   rows), *_calibration_curve(doc)]


def _calibration_curve(doc: dict[str, Any]) -> list[str]:
    """The KR60's accuracy against the tour's poses: median and worst of the runs per count."""
    curve = doc["settings"].get("curve") or {}
    if not curve:
        return []

    def mm(v: Any) -> str:
        return "-" if v is None else f"{v * 1e3:.3f}"

    rows = [[n, str(c["runs"]), mm(c.get("median_calibrated_m")),
             mm(c.get("worst_calibrated_m")), mm(c.get("median_calibrated_rad")),
             mm(c.get("worst_calibrated_rad")), fmt_s(c.get("median_seconds"))]
            for n, c in sorted(curve.items(), key=lambda kv: int(kv[0]))]
    return ["KR60 tool0 after calibration against the tour's poses (runs with different "
            "seeds per count):", "",
            *table(["poses", "runs", "median mm", "worst mm", "median mrad", "worst mrad",
                    "median urdf s"], rows), "", "![Calibration](calibrate.png)", ""]


def workspace_section(doc: dict[str, Any]) -> list[str]:
    reach = doc["cases"]["KR60 reach"]
    res, n_o = reach["settings"]["resolution_m"], reach["settings"]["orientations"]
    def runs_of(r: dict[str, Any], key: str) -> str:
        every = r.get(f"{key}_all")
        return fmt_s(r[key]) + (f" ({', '.join(fmt_s(x) for x in every)})"
                                if every and len(every) > 1 else "")

    rows = [[label, runs_of(r, "wall_seconds"), runs_of(r, "job_seconds"),
             "-" if r.get("edge_seconds") is None else fmt_s(r["edge_seconds"]),
             f"{r['queries']:,}", str(r["workers"]),
             f"{r['queries_per_second_per_worker'] or 0:,.0f}", f"{r['voxels_reached']:,}"]
            for label, r in reach["runs"].items()]
    j = reach["judge"]
    place = doc["cases"]["KR60 place"]
    best = place["best"]
    cycle = [[r["move"], f"{r['planning_s'] * 1e3:.1f}", f"{r['duration_s']:.2f}",
              "-" if r.get("true_tip_error_m") is None else f"{r['true_tip_error_m'] * 1e3:.2f}",
              "-" if r.get("true_tip_error_rad") is None else
              f"{r['true_tip_error_rad'] * 1e3:.2f}"] for r in place["cycle"]]
    return ["No peer builds an IK-verified, collision-aware reachability map; our figures, "
            "judged by the bench's own Pinocchio and python-fcl. `usar-arm reach` of the KR60 "
            f"(empty scene, {res} m voxels, {n_o} orientations), whole command (wall), the "
            "job alone (the voxel centres on the backend, workers' and Ray's start included) "
            "and the edge search (in the command's process); the median run, every run in "
            "brackets where runs alternated:", "",
            *table(["backend", "wall", "job", "edge search", "queries", "workers",
                    "queries/s per worker", "voxels reached"], rows), "",
            f"Maps identical across backends: {'yes' if reach['identical_maps'] else 'NO'}. "
            f"Judge: {j['witness_failures'] + j.get('edge_witness_failures', 0)} of "
            f"{j['witnesses']} sampled witnesses fail (max "
            f"{j['witness_max_position_m'] * 1e3:.4f} mm, {j['witness_max_rotation_rad'] * 1e3:.4f}"
            f" mrad from their voxel's centre and orientation; {j.get('edge_voxels', 0):,} edge "
            "voxels' witnesses inside their cell, nearest their orientation); of "
            f"{j['landings']:,} random "
            f"collision-free configurations, {fmt_pct(j['landed_fraction'])} land in a marked "
            f"voxel and {j['not_landed_beside_a_marked_voxel']} of the other "
            f"{j['not_landed']} beside one; {j['marked_beyond_sampled_reach']} marked voxels "
            f"lie beyond the reach sampled by FK ({j['sampled_reach_m']:.3f} m).", "",
            f"`usar-arm place` (table scene, the 6 targets of examples/workspace/"
            f"table-targets.yaml, {doc['settings']['place_step']} m grid): "
            f"{place['counts']['feasible']:,} of {place['counts']['within_reach']:,} base poses "
            f"reach every target; best at ({best['x']:.2f}, {best['y']:.2f}) m, yaw "
            f"{best['yaw_deg']:.0f} deg, score {best['score']:.3f} ({fmt_s(place['wall_seconds'])}"
            "). Its cycle through the targets on the embedded simulator (as-learnt KR60):", "",
            *table(["move", "plan ms", "motion s", "true mm", "true mrad"], cycle), ""]


def planners_section(doc: dict[str, Any]) -> list[str]:
    """The planners of ompl_planning.yaml, ranked (bench/planners.py)."""
    rows = [[str(k + 1), r["planner"], r["ompl"],
             f"{fmt_pct(r['success_rate'])} ({r['verified']}/{r['problems']})",
             fmt_s(r["median_s"]), fmt_s(r["p90_s"]), str(r["over_budget"]),
             str(r["paths_in_collision"])] for k, r in enumerate(doc["ranking"])]
    settings = doc["settings"]
    return ["Every OMPL planner the MoveIt package's `ompl_planning.yaml` offers, each through "
            "usar-arm's own OMPL adapter (`plan_to_joints`, "
            f"{settings['time_limit_s']:g} s budget), on {settings['problems']} (KR60, "
            "blocked straight lines, 4 scenes), judged as the plan stage judges; ranked by "
            "verified success, then median time. The YAML lists them in this order, the first "
            "as its default. The optimising planners (RRTstar, PRMstar) refine their path until "
            "the budget ends, by design: over budget counts calls that ended after it.",
            "", *table(["rank", "planner (MoveIt)", "OMPL class", "verified", "median", "p90",
                        "over budget", "paths in collision"], rows)]


SECTIONS = {"ik": ik_section, "collision": collision_section, "plan": plan_section,
            "timing": timing_section, "discovery": describe_section,
            "execution": execution_section, "calibrate": calibrate_section,
            "workspace": workspace_section, "planners": planners_section}


def _load(doc: dict[str, Any]) -> str:
    load = doc.get("machine", {}).get("load_average_1_5_15")
    return "load ?" if not load else f"load {load[0]:.1f}"


def generate(folder: Path, total_seconds: float | None = None) -> Path:
    """Write ``folder/README.md`` and the plots from the stage files found there."""
    docs = {s: common.read_json(folder / f"{s}.json") for s in SECTIONS
            if (folder / f"{s}.json").is_file()}
    run = common.read_json(folder / "run.json") if (folder / "run.json").is_file() else {}
    if total_seconds is None and run:
        total_seconds = run.get("wall_seconds_before_report")
    images = plots.draw_all(docs, folder)
    first = next(iter(docs.values()), {})
    m = first.get("machine", {})
    modes = sorted({d.get("mode", "?") for d in docs.values()})
    peers = sorted({f"{n} {s.get('version', '')}" for d in docs.values()
                    for c in d["cases"].values() for n, s in c.get("solvers", {}).items()
                    if s["kind"] == "peer" and "version" in s})
    skipped = sorted({f"{n} ({s['skipped']})" for d in docs.values()
                      for c in d["cases"].values() for n, s in c.get("solvers", {}).items()
                      if "skipped" in s})
    lines = ["# usar-arm benchmarks", "",
             "Generated by `bench/report.py` from the `*.json` files in this folder "
             f"({time.strftime('%Y-%m-%d %H:%M')}); do not edit. Reproduce with "
             "`make bench` (full) or `make bench-quick` (CI smoke run).", "",
             f"* Mode: {', '.join(modes)}"
             + (f"; whole run {total_seconds / 60:.1f} min" if total_seconds else "")
             + (f" (problem generation {run['problem_generation_seconds']:.0f} s)"
                if run.get("problem_generation_seconds") else "")
             + ("; stage times (load average at the stage's end): " + ", ".join(
                 f"{s} {d['wall_seconds'] / 60:.1f} min ({_load(d)})"
                 for s, d in docs.items())),
             f"* Machine: {m.get('cpu')}, {m.get('logical_cores')} logical cores, "
             f"{m.get('ram_gib')} GiB RAM, Python {m.get('python')}, {m.get('os')}",
             "* usar-arm and its libraries: " + ", ".join(
                 f"{k} {v}" for k, v in first.get("versions", {}).items()),
             "* Peers (each in its own venv, `bench/.venvs/<peer>`): " + (", ".join(peers)
                                                                         or "none"),
             "* Environment of every solver process: " + ", ".join(
                 f"{k}={v}" for k, v in first.get("environment", {}).items()), ""]
    if skipped:
        lines += ["* **Skipped**: " + "; ".join(skipped), ""]
    lines += [
        "How to read: every solver, ours included, runs in its own process on the same "
        "problem file; the problems are split into interleaved rounds and the solvers take "
        "turns round by round, so a noisy machine slows them alike. Times are per problem "
        "over every problem attempted (a failure costs its time). *Verified success* counts "
        "only answers that pass the harness's own checks: IK answers by Pinocchio FK within "
        "the tolerance and the limits; collision answers against a brute-force python-fcl "
        "judge; paths by the same judge at every configuration 0.005 rad apart (and found "
        "within the 2 s budget); trajectories by their end points, finite-difference "
        "velocity/acceleration and the judge. A fast wrong answer is a failure. Ratios are "
        "usar-arm's median / the peer's median in the same run (< 1: usar-arm is faster). "
        "OMPL seeds once per process, so our planning figures are reproducible per process; "
        "mplib and roboplan are seeded per problem.", ""]
    lines += targets_section(docs)
    for stage, doc in docs.items():
        lines += [f"## {STAGE_TITLES[stage]}", "", *SECTIONS[stage](doc)]
    path = folder / "README.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    common.log(f"report: {path} and {len(images)} plot(s)")
    return path


if __name__ == "__main__":
    generate(Path(sys.argv[1]) if len(sys.argv) > 1 else common.BENCH / "results")
