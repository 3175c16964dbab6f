"""Figures in prose that come from the benchmark's results, never typed by hand.

A figure in README.md, docs/*.md or tools/README.md is written inside a marker that says where
it comes from:

    <!-- fig execution.json#/cases/udk wire, no correction/max_m | *1e3 | .2f -->2.19<!-- /fig -->

``FILE#/a/b/c`` is a JSON pointer into ``bench/results/FILE`` (``*`` expands every item of a list
or every value of an object); then each ``|`` step: ``max``, ``min``, ``mean``, ``first``, ``len``,
``*K`` (multiply), ``/K`` (divide), ``/#/d/e`` (divide by the value at another pointer of the
same file), ``inv`` (1/x), and last a format (``.2f``, ``.3g``, ``,.0f``, ``.1%``). The
markers are HTML comments: invisible on GitHub and in the docs site.

``python tools/figures.py`` lists the figures that differ from the results (exit 1 when any
does); ``--write`` rewrites them. ``tests/test_figures.py`` runs the check, so prose cannot drift
from the measurement: a new full ``make bench`` is followed by ``--write``.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
MARKER = re.compile(r"<!-- fig (?P<spec>[^>]*?) -->(?P<value>[^<]*)<!-- /fig -->")


@dataclass(frozen=True)
class Figure:
    """One marked figure: its file, line, source spec, the text there and what it should be."""

    path: Path
    line: int
    spec: str
    written: str
    expected: str


def _pointer(doc: Any, pointer: str) -> list[Any]:
    values = [doc]
    for part in [p for p in pointer.split("/") if p]:
        step: list[Any] = []
        for v in values:
            if part == "*":
                step.extend(v.values() if isinstance(v, dict) else v)
            elif isinstance(v, list):
                step.append(v[int(part)])
            else:
                if part not in v:
                    raise KeyError(f"no '{part}' (keys: {', '.join(map(str, v))[:300]})")
                step.append(v[part])
        values = step
    return values


def evaluate(spec: str, results: Path = RESULTS) -> str:
    """The text of a figure from its spec (see the module's docstring)."""
    source, *steps = [s.strip() for s in spec.split("|")]
    name, _, pointer = source.partition("#")
    doc = json.loads((results / name).read_text())
    values: Any = _pointer(doc, pointer)
    value: Any = values[0] if len(values) == 1 else values
    fmt = steps.pop() if steps and not steps[-1].startswith(("*", "/")) and steps[-1] not in (
        "max", "min", "mean", "first", "len", "inv") else ""
    for step in steps:
        if step in ("max", "min"):
            value = (max if step == "max" else min)(value)
        elif step == "mean":
            value = sum(value) / len(value)
        elif step == "first":
            value = value[0]
        elif step == "len":
            value = len(value)
        elif step == "inv":
            value = 1.0 / value
        elif step.startswith("/#"):
            value = value / _pointer(doc, step[2:])[0]
        elif step.startswith("*"):
            value = value * float(step[1:])
        elif step.startswith("/"):
            value = value / float(step[1:])
        else:
            raise ValueError(f"unknown step '{step}' in '{spec}'")
    return format(value, fmt) if fmt else str(value)


def documents(root: Path = ROOT) -> list[Path]:
    """README.md, every Markdown page under docs/, and tools/README.md."""
    return [root / "README.md", *sorted((root / "docs").rglob("*.md")),
            root / "tools" / "README.md"]


def figures(paths: list[Path], results: Path = RESULTS) -> Iterator[Figure]:
    """Every marked figure of ``paths`` with the text the results give it."""
    for path in paths:
        text = path.read_text()
        for match in MARKER.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            try:
                expected = evaluate(match["spec"], results)
            except (KeyError, IndexError, ValueError, TypeError, OSError) as exc:
                expected = f"<error: {exc}>"
            yield Figure(path, line, match["spec"], match["value"], expected)


def rewrite(path: Path, results: Path = RESULTS) -> int:
    """Rewrite the marked figures of ``path`` from the results; how many changed."""
    text = path.read_text()
    changed = 0

    def render(match: re.Match[str]) -> str:
        nonlocal changed
        value = evaluate(match["spec"], results)
        changed += value != match["value"]
        return f"<!-- fig {match['spec']} -->{value}<!-- /fig -->"

    new = MARKER.sub(render, text)
    if changed:
        path.write_text(new)
    return changed


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--write", action="store_true", help="rewrite the figures in place")
    args = parser.parse_args()
    if args.write:
        total = sum(rewrite(p) for p in documents())
        print(f"{total} figure(s) rewritten from bench/results")
        return 0
    stale = [f for f in figures(documents()) if f.written != f.expected]
    for f in stale:
        print(f"{f.path.relative_to(ROOT)}:{f.line}: {f.written!r} but the results give "
              f"{f.expected!r} ({f.spec})")
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
