"""The benchmark report's formatting: figures in the unit that reads best, Markdown tables and
the per-solver rows every stage's table shares (``bench/report.py`` writes the README)."""

from __future__ import annotations

from typing import Any

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


def row(cells: list[str]) -> str:
    return "| " + " | ".join(c.replace("|", "/") for c in cells) + " |"


def table(head: list[str], rows: list[list[str]]) -> list[str]:
    return [row(head), row(["---"] * len(head)), *(row(r) for r in rows), ""]


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
                ("answered_after_budget", "after the 2 s budget"),
                ("in_self_collision", "in self-collision")) if sm.get(k)]
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
