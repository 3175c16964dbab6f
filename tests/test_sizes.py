"""The quality bar's sizes (issue 24): no function or method of usar_arm over 80 lines
(compiled kernels included), no class over 300, no module over 450; a line is any line of the
unit's source, its docstring, comments and blank lines included."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "usar_arm"
MAX_FUNCTION, MAX_CLASS, MAX_MODULE = 80, 300, 450

def _long_units(path: Path) -> list[str]:
    text = path.read_text()
    name = path.relative_to(PACKAGE).as_posix()
    out = []
    lines = len(text.splitlines())
    if lines > MAX_MODULE:
        out.append(f"{name}: module of {lines} lines (> {MAX_MODULE})")
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            first = min([node.lineno, *(d.lineno for d in node.decorator_list)])
            size = (node.end_lineno or node.lineno) - first + 1
            limit = MAX_CLASS if isinstance(node, ast.ClassDef) else MAX_FUNCTION
            if size > limit:
                out.append(f"{name}:{node.lineno} {node.name}: {size} lines (> {limit})")
    return out


def test_no_unit_is_over_its_size() -> None:
    found = [line for path in sorted(PACKAGE.rglob("*.py")) for line in _long_units(path)]
    assert not found, "too long:\n" + "\n".join(found)

