"""VAMP in the ``robots`` stage: its planner beside usar-arm's on the same MotionBenchMaker
problems when a local build is present (``bench/peers/venvs.py`` finds it, the runner is
``bench/peers/run_vamp_plan.py``), timed both ways (its own timer, the Python call), its paths
judged by the stage's mesh judge on example-robot-data's meshes like every other solver's; and
the figures VAMP's authors publish, quoted as published, never as measured here.
"""

from __future__ import annotations

from typing import Any

import common
import robots_data as data
import venvs

PUBLISHED = {
    "status": "published by VAMP's authors, not measured here",
    "source": f"github.com/KavrakiLab/vamp resources/README.md at {data.VAMP_COMMIT}, "
              "'Reference Timings' of scripts/evaluate_mbm.py with default planner settings "
              "(RRT-Connect, dynamic domain), all 7 MBM sets of a robot together (700 problems)",
    "machine": "AMD Ryzen 9 7950X (one core)",
    "collision_model": "VAMP's sphere approximations of robowflex_resources' UR5 (with a "
                       "Robotiq 85 gripper) and Panda (with hand): not example-robot-data's "
                       "meshes",
    "paper": "W. Thomason, Z. Kingston, L. E. Kavraki, 'Motions in Microseconds via Vectorized "
             "Sampling-Based Planning', ICRA 2024 (arXiv 2309.14545): median 35 us for the "
             "Panda on MBM, one core of a consumer desktop PC (README)",
    "per_set": "the README gives no per-set figures; per-set tables are in the paper only "
               "(not copied here)",
    "ur5": {"planning_us": {"median": 39, "mean": 160.523, "p95": 776.05},
            "simplification_us": {"median": 54, "mean": 65.7484},
            "total_us": {"median": 111.5, "mean": 226.794, "p95": 836.65},
            "solved_valid_total": [608, 608, 700]},
    "panda": {"planning_us": {"median": 35, "mean": 76.1989, "p95": 343.3},
              "simplification_us": {"median": 57, "mean": 67.408},
              "total_us": {"median": 99, "mean": 144.116, "p95": 441.6},
              "solved_valid_total": [699, 699, 700]}}
"""VAMP's published reference timings (never measured here)."""

NOTE = ("RRT-Connect + simplify on its sphere model of robowflex's robot, halton sampler reset "
        "per problem; seconds = the Python calls, own_seconds = its own timer")
OWN_TIMES = ("own_seconds", "plan_own_seconds", "simplify_own_seconds")
"""Per-problem figures of VAMP's results passed through to the case's raw columns (s)."""


def solver(ctx: common.Context) -> common.Solver:
    """VAMP's planner as a peer of the plan task (skipped, saying how to build it, without a
    local build)."""
    return ctx.peer("vamp", "plan", NOTE)


def passthrough(r: dict[str, Any]) -> dict[str, Any]:
    """The timer figures of a VAMP result (None for the other solvers' results)."""
    return {k: r.get(k) for k in OWN_TIMES}


def own_time_summary(raw: dict[str, list[Any]]) -> dict[str, Any]:
    """Distributions of VAMP's own timer (s) over every problem it answered and over its
    verified answers; nothing for a solver without that timer."""
    own = raw.get("own_seconds") or []
    if not any(v is not None for v in own):
        return {}
    verified = raw.get("verified") or [False] * len(own)
    out = {"own_time_all_s": common.stats(own),
           "own_time_verified_s": common.stats([t for t, v in zip(own, verified, strict=True)
                                                if v])}
    for key in ("plan_own_seconds", "simplify_own_seconds"):
        out[key.replace("_seconds", "_s")] = common.stats(raw.get(key) or [])
    return out


def row(plan: dict[str, Any]) -> dict[str, Any]:
    """VAMP's measured row for one robot's plan case (its medians both ways, its paths judged on
    the meshes, usar-arm's median and the ratios), or why it was not measured."""
    s = plan.get("solvers", {}).get("vamp", {})
    if "skipped" in s or not s:
        return {"measured": False, "skipped": s.get("skipped", "not run")}
    sm = s.get("summary", {})
    ours = (plan["solvers"].get("usar-arm", {}).get("summary", {}).get("time_all_s") or {})
    own = (sm.get("own_time_all_s") or {}).get("median")
    call = (sm.get("time_all_s") or {}).get("median")
    return {"measured": True, "version": s.get("version"), "problems": sm.get("problems"),
            "answered": sm.get("answered"), "verified_on_meshes": sm.get("verified"),
            "paths_in_collision_on_meshes": sm.get("paths_in_collision"),
            "median_call_s": call, "median_own_s": own,
            "median_plan_own_s": (sm.get("plan_own_s") or {}).get("median"),
            "median_simplify_own_s": (sm.get("simplify_own_s") or {}).get("median"),
            "usar_arm_median_s": ours.get("median"),
            "ratio_usar_to_vamp_call": common.ratio(ours.get("median"), call),
            "ratio_usar_to_vamp_own": common.ratio(ours.get("median"), own)}


def summary(cases: dict[str, Any]) -> dict[str, Any]:
    """``robots.json``'s ``vamp``: per robot, VAMP's measured row beside usar-arm's median (or
    why it was not run), and how a build is found or made."""
    out: dict[str, Any] = {"venv": str(venvs.external_venv("vamp")),
                           "ready": venvs.is_ready("vamp"),
                           "how_to_build": venvs.EXTERNAL["vamp"]["how"],
                           "built": venvs.EXTERNAL["vamp"]["built"],
                           "collision_model": PUBLISHED["collision_model"],
                           "machine_note": "measured beside usar-arm in alternating rounds "
                                           "on the stage's machine"}
    for key in ("ur5", "panda"):
        plan = cases.get(f"robots_{key}_plan", {})
        out[key] = row(plan) if plan else {"measured": False, "skipped": "no plan case"}
    return out
