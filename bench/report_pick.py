"""The pick-and-place stage's section of bench/results/README.md."""

from __future__ import annotations

from typing import Any

from report_format import table


def pick_place_section(doc: dict[str, Any]) -> list[str]:
    """One row per seeded run: where the part came to rest and the contacts, by the
    simulator."""
    out: list[str] = []
    for name, case in doc["cases"].items():
        s = case["solvers"]["usar-arm"]
        raw, sm = s.get("raw") or {}, s.get("summary") or {}
        out += [f"### {name}: {sm.get('placed')} of {sm.get('runs')} runs placed, "
                f"{sm.get('contacts')} contacts", ""]
        for err in sm.get("errors") or []:
            out += [f"Failed: {err}", ""]
        rows = []
        for k, placed in enumerate(raw.get("placed", [])):
            def g(key: str, scale: float = 1.0, fmt: str = ".2f", k: int = k,
                  raw: dict[str, Any] = raw) -> str:
                v = (raw.get(key) or [None] * (k + 1))[k]
                return "-" if v is None else f"{v * scale:{fmt}}"

            shift = raw.get("shift_m", [[0.0, 0.0]] * (k + 1))[k]
            rows.append([str(k), f"{shift[0] * 1e3:+.0f}, {shift[1] * 1e3:+.0f}",
                         "yes" if placed else "no", g("xy_error_m", 1e3),
                         g("floor_gap_m", 1e3, "+.2f"), g("arm_contacts", 1, ".0f"),
                         g("carried_contacts", 1, ".0f"), g("max_true_tip_error_m", 1e3),
                         g("run_seconds", 1, ".1f")])
        out += table(["seed", "part shifted mm", "placed", "from the place mm",
                      "above the bin's floor mm", "arm/tool contacts", "carried contacts",
                      "worst tool0 error mm", "run s"], rows)
    return out
