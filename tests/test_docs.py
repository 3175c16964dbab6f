"""The project cites only its own documents: every ``docs/X.md`` named in the code, the tests, the
benchmark, the tools and the README exists, every section it names exists, and nothing cites the
notes the project was started from (they are not in the repository). The README stays short and
leads to every page; what it shows (commands, the library example) is what the package has."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
SOURCES = [p for folder in ("usar_arm", "tests", "bench", "tools", "fuzz", "examples", "docs")
           for p in (ROOT / folder).rglob("*")
           if p.suffix in (".py", ".md", ".yaml", ".yml", ".toml", ".txt")
           and ".venvs" not in p.parts and "results" not in p.parts]
SOURCES += [ROOT / "README.md", ROOT / "Makefile"]
CITATION = re.compile(r"docs/([a-z_-]+\.md)(?:\s*\(?\s*sections?\s+"
                      r"([0-9][0-9.]*(?:(?:,\s*|\s+and\s+)[0-9][0-9.]*)*))?")
# Pages written in parallel on issue 24 that the README already links: each is checked like any
# other as soon as it exists. When one lands, add it to mkdocs.yml's nav and docs/index.md, and
# remove it from here (the site's nav test then requires it).
PENDING: set[str] = set()
README = ROOT / "README.md"
OUTSIDE = re.compile(r"usarsim-protocol\.md|ros-conventions\.md|DESIGN\.md|shared/reference"
                     r"|(?<![/-])\bpeers\.md")


def _sections(doc: Path) -> set[str]:
    return {m.group(1).rstrip(".") for m in
            re.finditer(r"^#{2,4}\s+([0-9][0-9.]*)\s", doc.read_text(), flags=re.MULTILINE)}


def _texts() -> list[tuple[Path, str]]:
    return [(p, p.read_text(errors="replace")) for p in SOURCES
            if p.is_file() and p.name != "test_docs.py"]


def test_every_cited_document_and_section_exists() -> None:
    cited = 0
    for path, text in _texts():
        for m in CITATION.finditer(text):
            doc = ROOT / "docs" / m.group(1)
            if m.group(1) in PENDING and not doc.is_file():
                continue
            assert doc.is_file(), f"{path.relative_to(ROOT)} cites docs/{m.group(1)}: missing"
            cited += 1
            if m.group(2):
                known = _sections(doc)
                for number in re.split(r",\s*|\s+and\s+", m.group(2)):
                    number = number.rstrip(".")
                    assert number in known, (f"{path.relative_to(ROOT)} cites docs/{m.group(1)} "
                                             f"section {number}; it has {sorted(known)}")
    assert cited >= 10, "the code is expected to point into docs/ in many places"


def test_nothing_cites_a_document_outside_the_repository() -> None:
    found = [f"{path.relative_to(ROOT)}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)}"
             for path, text in _texts() for m in OUTSIDE.finditer(text)]
    assert not found, "citations of documents outside the repository:\n" + "\n".join(found)


def test_the_documents_the_readme_promises_exist() -> None:
    for name in ("architecture.md", "protocol.md", "conventions.md", "measuring.md", "peers.md",
                 "cli.md", "performance.md", "limitations.md", "calibration.md", "workspace.md"):
        assert (ROOT / "docs" / name).is_file(), name


def _readme_links() -> set[str]:
    return set(re.findall(r"\]\(docs/([^)#]+)", README.read_text()))


def test_the_readme_is_short_and_leads_to_every_page() -> None:
    lines = README.read_text().count("\n")
    assert lines < 200, f"README.md has {lines} lines: move the detail into docs/"
    linked = _readme_links()
    for name in linked - PENDING:
        assert (ROOT / "docs" / name).is_file(), f"README.md links docs/{name}: missing"
    pages = {p.name for p in (ROOT / "docs").glob("*.md")}
    assert pages - linked - {"index.md"} == set(), "pages no README link leads to"
    assert (ROOT / "docs" / "api" / "arm.md").is_file() and "api/arm.md" in linked
    assert "ros.md" in linked  # the ROS 2 page's place in the list


def test_the_site_shows_every_page() -> None:
    config = yaml.load((ROOT / "mkdocs.yml").read_text(), Loader=yaml.BaseLoader)

    def pages(node: object) -> list[str]:
        if isinstance(node, str):
            return [node]
        if isinstance(node, dict):
            return [p for v in node.values() for p in pages(v)]
        if isinstance(node, list):
            return [p for v in node for p in pages(v)]
        return []

    nav = set(pages(config["nav"]))
    docs = ROOT / "docs"
    every = {str(p.relative_to(docs)) for p in docs.rglob("*.md")} - PENDING
    assert every - nav == set(), "pages missing from mkdocs.yml's nav"
    assert nav - every == set(), "mkdocs.yml's nav names pages that do not exist"
    packages = sorted(p.parent.name for p in (ROOT / "usar_arm").glob("*/__init__.py"))
    assert {f"api/{p}.md" for p in packages} <= nav, "a subpackage without its API page"
    for package in packages:
        assert f"::: usar_arm.{package}" in (docs / "api" / f"{package}.md").read_text()


def test_the_readme_lists_every_command() -> None:
    from usar_arm.cli.commands import COMMANDS  # usar-arm --help's commands, in its order

    listed = re.findall(r"^\| `usar-arm ([a-z-]+)", README.read_text(), flags=re.MULTILINE)
    commands = list(COMMANDS)
    assert listed == commands, "README's command table and usar-arm --help differ"
    reference = (ROOT / "docs" / "cli.md").read_text()
    for command in commands:
        assert f"usar-arm {command}" in reference, f"docs/cli.md does not show {command}"


def _readme_example() -> str:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.DOTALL)
    assert len(blocks) == 1, "the README has one library example"
    return blocks[0]


def test_the_readme_example_uses_only_public_names() -> None:
    import importlib

    code = _readme_example()
    assert len([line for line in code.splitlines() if line and not line.startswith(
        ("import", "from"))]) <= 5, "the library example is five lines"
    for node in ast.walk(ast.parse(code)):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("usar_arm"):
            package = importlib.import_module(node.module)
            for alias in node.names:
                assert alias.name in package.__all__, f"{node.module}.{alias.name} is not public"


@pytest.mark.slow
def test_the_readme_example_runs() -> None:
    done = subprocess.run([sys.executable, "-c", _readme_example()], cwd=ROOT, text=True,
                          capture_output=True, timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    assert len(done.stdout.split()) >= 2, done.stdout
