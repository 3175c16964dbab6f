"""The project cites only its own documents: every ``docs/X.md`` named in the code, the tests, the
benchmark, the tools and the README exists, every section it names exists, and nothing cites the
notes the project was started from (they are not in the repository)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCES = [p for folder in ("usar_arm", "tests", "bench", "tools", "fuzz", "examples", "docs")
           for p in (ROOT / folder).rglob("*")
           if p.suffix in (".py", ".md", ".yaml", ".yml", ".toml", ".txt")
           and ".venvs" not in p.parts and "results" not in p.parts]
SOURCES += [ROOT / "README.md", ROOT / "Makefile"]
CITATION = re.compile(r"docs/([a-z_-]+\.md)(?:\s*\(?\s*sections?\s+"
                      r"([0-9][0-9.]*(?:(?:,\s*|\s+and\s+)[0-9][0-9.]*)*))?")
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
    for name in ("architecture.md", "protocol.md", "conventions.md", "measuring.md", "peers.md"):
        assert (ROOT / "docs" / name).is_file(), name
