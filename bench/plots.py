"""PNG plots of the benchmark results (matplotlib object API on the Agg canvas, no pyplot).

Distributions are box plots of the per-problem figures (box: quartiles, whiskers: 5th-95th
percentile, dot: mean), usar-arm's solvers in orange beside each peer.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

OURS = "tab:orange"
PEER_COLORS = {"pytracik": "tab:blue", "mplib": "tab:green", "roboplan": "tab:purple",
               "opw": "tab:brown", "ikpy": "tab:gray", "toppra": "tab:cyan"}


def _color(name: str, kind: str) -> str:
    return OURS if kind == "ours" else PEER_COLORS.get(name, "tab:olive")


def _line(name: str, color: str) -> dict[str, str]:
    """Line style of a series: ours solid (a second API of ours dotted, square markers),
    peers dashed."""
    if color != OURS:
        return {"linestyle": "--", "marker": "o", "color": color}
    second = name != "usar-arm"
    return {"linestyle": ":" if second else "-", "marker": "s" if second else "o",
            "color": color}


def _save(fig: Figure, path: Path) -> Path:
    FigureCanvasAgg(fig)
    fig.savefig(path, dpi=110)
    return path


def _times(s: dict[str, Any], key: str = "seconds", scale: float = 1e3) -> list[float]:
    raw = s.get("raw") or {}
    return [v * scale for v in raw.get(key, []) if v is not None]


def _boxes(ax: Any, case: dict[str, Any], title: str, unit: str = "ms",
           key: str = "seconds", scale: float = 1e3, log: bool = True) -> None:
    labels, data, colors = [], [], []
    for name, s in case["solvers"].items():
        values = _times(s, key, scale)
        if not values:
            continue
        sm = s.get("summary") or {}
        rate = sm.get("success_rate")
        labels.append(f"{name}\n{100 * rate:.1f} % ok" if rate is not None else name)
        data.append(values)
        colors.append(_color(name, s["kind"]))
    if not data:
        ax.set_axis_off()
        return
    bp = ax.boxplot(data, vert=False, whis=(5, 95), showfliers=False, patch_artist=True,
                    medianprops={"color": "black"})
    for patch, c in zip(bp["boxes"], colors, strict=True):
        patch.set_facecolor(c)
        patch.set_alpha(0.7)
    for k, values in enumerate(data):
        ax.plot(np.mean(values), k + 1, "o", color="black", markersize=3)
    ax.set_yticks(range(1, len(labels) + 1), labels, fontsize=8)
    ax.invert_yaxis()
    if log:
        ax.set_xscale("log")
    ax.set_xlabel(f"per problem ({unit})")
    ax.set_title(title, fontsize=10)
    ax.grid(True, axis="x", which="both", alpha=0.3)


def ik(doc: dict[str, Any], folder: Path) -> Path:
    cases = doc["cases"]
    fig = Figure(figsize=(5.5 * max(2, len(cases)),
                          1.2 + 0.55 * max(len(c["solvers"]) for c in cases.values())))
    axes = fig.subplots(1, len(cases), squeeze=False)[0]
    for ax, (name, case) in zip(axes, cases.items(), strict=True):
        _boxes(ax, case, f"IK {name} ({case['dof']} joints): time per pose")
    fig.tight_layout()
    return _save(fig, folder / "ik.png")


def collision(doc: dict[str, Any], folder: Path) -> Path:
    fig = Figure(figsize=(8, 3.2))
    ax = fig.subplots()
    _boxes(ax, doc["cases"]["table"], "Collision check, KR60 in table", unit="us", scale=1e6)
    fig.tight_layout()
    return _save(fig, folder / "collision.png")


def plan(doc: dict[str, Any], folder: Path) -> Path:
    cases = {n: c for n, c in doc["cases"].items() if not n.startswith("boxes_")}
    fig = Figure(figsize=(11, 3.2))
    axes = fig.subplots(1, len(cases), squeeze=False)[0]
    for ax, (name, case) in zip(axes, cases.items(), strict=True):
        _boxes(ax, case, f"Planning + simplification, {name} ({case['dof']} joints)")
    fig.tight_layout()
    return _save(fig, folder / "plan.png")


def timing(doc: dict[str, Any], folder: Path) -> Path:
    case = doc["cases"]["KR60"]
    fig = Figure(figsize=(11, 3.2))
    a, b = fig.subplots(1, 2)
    _boxes(a, case, "Computation time per trajectory")
    _boxes(b, case, "Trajectory duration / toppra's (same path, same limits)", unit="ratio",
           key="ratio_to_toppra", scale=1.0, log=False)
    b.axvline(1.25, color="red", linestyle="--", linewidth=1)
    fig.tight_layout()
    return _save(fig, folder / "timing.png")


def _series(cases: dict[str, Any], stat: str) -> dict[str, tuple[list[int], list[float], str]]:
    out: dict[str, tuple[list[int], list[float], str]] = {}
    for name, case in cases.items():
        if not name.startswith("boxes_"):
            continue
        for solver, s in case["solvers"].items():
            value = ((s.get("summary") or {}).get("time_all_s") or {}).get(stat)
            if value is None or not (s.get("summary") or {}).get("answered"):
                continue
            xs, ys, _ = out.setdefault(solver, ([], [], _color(solver, s["kind"])))
            xs.append(case["obstacles"])
            ys.append(value * 1e3)
    return out


def scaling_obstacles(docs: dict[str, Any], folder: Path) -> Path | None:
    panels = [(d, t, st) for d, t, st in ((docs.get("collision"), "Collision check (mean)",
                                           "mean"),
                                          (docs.get("plan"), "Planning (median)", "median"))
              if d is not None]
    if not panels:
        return None
    fig = Figure(figsize=(11, 3.6))
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    for ax, (doc, title, stat) in zip(axes, panels, strict=True):
        for solver, (xs, ys, color) in _series(doc["cases"], stat).items():
            ax.plot(xs, ys, label=solver, **_line(solver, color))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("boxes in the scene")
        ax.set_ylabel("ms per problem")
        ax.set_title(f"{title} against obstacles, KR60", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, folder / "scaling_obstacles.png")


def scaling_joints(docs: dict[str, Any], folder: Path) -> Path | None:
    panels = []
    if "ik" in docs:
        panels.append(("IK mean time per pose", {
            n: c for n, c in docs["ik"]["cases"].items() if c.get("set", "uniform") == "uniform"},
            "mean"))
    if "plan" in docs:
        panels.append(("Planning median time", {n: c for n, c in docs["plan"]["cases"].items()
                                                if not n.startswith("boxes_")}, "median"))
    if not panels:
        return None
    fig = Figure(figsize=(11, 3.6))
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    for ax, (title, cases, stat) in zip(axes, panels, strict=True):
        solvers: dict[str, tuple[list[int], list[float], str]] = {}
        for case in cases.values():
            for name, s in case["solvers"].items():
                v = ((s.get("summary") or {}).get("time_all_s") or {}).get(stat)
                if v is None:
                    continue
                xs, ys, _ = solvers.setdefault(name, ([], [], _color(name, s["kind"])))
                xs.append(case["dof"])
                ys.append(v * 1e3)
        for name, (xs, ys, color) in solvers.items():
            ax.plot(xs, ys, label=name, **_line(name, color))
        ax.set_yscale("log")
        ax.set_xticks([6, 7], ["KR60\n6 revolute", "Fanuc_M16iB20\n7 (rail + 6)"])
        ax.set_xlim(5.7, 7.3)
        ax.set_ylabel("ms")
        ax.set_title(f"{title} against the number of joints", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return _save(fig, folder / "scaling_joints.png")


def describe(doc: dict[str, Any], folder: Path) -> Path:
    fig = Figure(figsize=(8, 3))
    ax = fig.subplots()
    keys = {"start-up (interpreter, imports)": "startup_seconds",
            "discovery (TCP)": "discovery_seconds", "build + checks + ACM": "build_seconds",
            "write": "write_seconds"}
    names: list[str] = []
    parts: dict[str, list[float]] = {label: [] for label in keys}
    for name, case in doc["cases"].items():
        sm = case["solvers"]["usar-arm"].get("summary") or {}
        names.append(name)
        for label, key in keys.items():
            parts[label].append((sm.get(key) or {}).get("median") or 0.0)
    left = np.zeros(len(names))
    for (label, values), color in zip(parts.items(), ("tab:olive", OURS, "tab:red",
                                                       "tab:gray"), strict=True):
        ax.barh(names, values, left=left, color=color, label=label)
        left += np.array(values)
    ax.invert_yaxis()
    ax.set_xlabel("s (median)")
    ax.set_title("A fresh process: time to learn and describe an arm", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, folder / "discovery.png")


def execution(doc: dict[str, Any], folder: Path) -> Path:
    fig = Figure(figsize=(11, 3.4))
    a, b = fig.subplots(1, 2)
    cases = list(doc["cases"].items())
    width = 0.8 / max(1, len(cases))
    for k, (name, case) in enumerate(cases):
        raw = case["solvers"]["usar-arm"].get("raw") or {}
        moves = raw.get("move", [])
        x = np.arange(len(moves)) + k * width
        err = [max(1e3 * (v or 0.0), 1e-3) for v in raw.get("true_tip_error_m", [])]
        trk = [1e3 * (v or 0.0) for v in raw.get("max_tracking_error_rad", [])]
        a.bar(x, err, width, label=name)
        b.bar(x, trk, width, label=name)
        if k == 0:
            a.set_xticks(np.arange(len(moves)) + 0.4 - width / 2, moves, fontsize=8)
            b.set_xticks(np.arange(len(moves)) + 0.4 - width / 2, moves, fontsize=8)
    a.axhline(1.0, color="red", linestyle="--", linewidth=1)
    b.axhline(10.0, color="red", linestyle="--", linewidth=1)
    a.set_yscale("log")
    a.set_ylabel("mm")
    a.set_title("Final tool0 position error (simulator physics)", fontsize=10)
    b.set_ylabel("mrad")
    b.set_title("Max tracking error", fontsize=10)
    a.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, folder / "execution.png")


def calibration(doc: dict[str, Any], folder: Path) -> Path | None:
    """tool0's error after calibration against the tour's poses: every run, the median and
    the worst per count, the 0.2 mm target; and the time of `usar-arm urdf`."""
    curve = (doc.get("settings") or {}).get("curve") or {}
    if not curve:
        return None
    fig = Figure(figsize=(10, 3.4))
    a, b = fig.subplots(1, 2)
    counts = sorted(int(n) for n in curve)
    for ax, key, scale, unit, title in (
            (a, "calibrated_m", 1e3, "mm", "tool0 position error after calibration"),
            (b, "seconds", 1.0, "s", "usar-arm urdf with calibration")):
        for n in counts:
            values = [v * scale for v in curve[str(n)][key] if v is not None]
            ax.plot([n] * len(values), values, "o", color=OURS, alpha=0.45, markersize=4)
        for stat, style in (("median", "-"), ("worst", "--")):
            ys = [curve[str(n)].get(f"{stat}_{key}") for n in counts]
            xs = [n for n, y in zip(counts, ys, strict=True) if y is not None]
            ax.plot(xs, [y * scale for y in ys if y is not None], style, color=OURS,
                    label=f"{stat} of the runs per count")
        ax.set_xlabel("poses in the tour")
        ax.set_ylabel(unit)
        ax.set_xticks(counts)
        ax.set_title(title, fontsize=10)
        ax.grid(True, alpha=0.3)
    a.axhline(0.2, color="red", linestyle="--", linewidth=1, label="target 0.2 mm")
    b.axhline(45.0, color="red", linestyle="--", linewidth=1, label="budget 45 s")
    a.set_ylim(bottom=0)
    a.legend(fontsize=7)
    b.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, folder / "calibrate.png")


def draw_all(docs: dict[str, Any], folder: Path) -> list[Path]:
    """Every plot the present stage files allow."""
    out: list[Path | None] = []
    simple = {"ik": ik, "collision": collision, "plan": plan, "timing": timing,
              "discovery": describe, "execution": execution}
    for stage, fn in simple.items():
        if stage in docs:
            out.append(fn(docs[stage], folder))
    if "calibrate" in docs:
        out.append(calibration(docs["calibrate"], folder))
    out.append(scaling_obstacles(docs, folder))
    out.append(scaling_joints(docs, folder))
    return [p for p in out if p is not None]
