"""The project's web pages, opened as a user opens them: ``usar-arm view``'s 3D replay and the
documentation site, in headless Chromium (tools/browser.py; Debian's ``chromium`` package is
installed where apt-get can, else these tests skip with the command that installs it).

The viewer: the page loads, the browser reports no error, the 3D view draws the arm (pixels
that are not the background, which change as the replay plays) and its time box shows its whole
value. The site (built with ``make docs``' venv): the API reference renders the docstrings'
sections as sections, every cross-reference as a link to an anchor that exists, no literal
role or ``~usar_arm`` text, no signature line wider than the page, and its pages load with no
browser error (issue 39, items 4 and 9).
"""

from __future__ import annotations

import functools
import html
import http.server
import re
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import browser  # noqa: E402

DOCS_MKDOCS = ROOT / ".venv-docs" / "bin" / "mkdocs"
SIGNATURE_COLUMNS = 100
"""The widest signature line the page shows without a scroll bar (characters)."""


@pytest.fixture(scope="module")
def chromium() -> str:
    try:
        return browser.chromium()
    except browser.BrowserUnavailable as exc:
        pytest.skip(str(exc))


# ------------------------------------------------------------------ usar-arm view


@pytest.fixture(scope="module")
def viewer(tmp_path_factory: pytest.TempPathFactory, chromium: str) -> Iterator[str]:
    pytest.importorskip("viser")
    folder = tmp_path_factory.mktemp("viewer")
    subprocess.run([sys.executable, "-m", "usar_arm", *(
        a.replace("{root}", str(ROOT)) for a in browser.PLAN), "-q"], cwd=folder, check=True,
        timeout=600)
    process, url = browser.serve_view(folder / "traj.json", folder)  # (no --scene)
    try:
        yield url
    finally:
        process.kill()
        process.wait(timeout=30)


def test_the_viewer_draws_the_arm_replaying_with_no_browser_error(viewer: str) -> None:
    with browser.Page.open(1280, 800) as page:
        page.goto(viewer)
        page.wait_for(browser.VIEWER_READY, timeout=600)
        page.pump(3.0)
        first = browser.pixels(page.screenshot())
        page.pump(1.0)
        later = browser.pixels(page.screenshot())
        boxes = page.evaluate("Array.from(document.querySelectorAll('input')).filter(i => "
                              "i.value !== '' && i.type !== 'checkbox').map(i => [i.value, "
                              "i.scrollWidth, i.clientWidth])")
        assert browser.page_errors(page) == []
    view = first[150:, :900]  # (the 3D view, left of the control panel)
    drawn = (view.min(axis=2) < 200).mean()
    assert drawn > 0.02, f"the 3D view is blank: {drawn:.1%} of its pixels drawn"
    moved = np.abs(first[150:, :900].astype(int) - later[150:, :900]).max(axis=2) > 30
    assert moved.mean() > 0.0005, "nothing moved between two frames of the replay"
    assert boxes, "the page shows no value boxes (speed, time)"
    cut = [value for value, scroll, client in boxes if scroll > client]
    assert cut == [], f"boxes cut off their values: {cut}"


# ------------------------------------------------------------------ the documentation site


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if not DOCS_MKDOCS.is_file():
        pytest.skip("no docs venv: make .venv-docs/.installed (make test creates it)")
    out = tmp_path_factory.mktemp("site")
    done = subprocess.run([str(DOCS_MKDOCS), "build", "--strict", "--site-dir", str(out)],
                          cwd=ROOT, capture_output=True, text=True, timeout=900, check=False,
                          env={"NO_MKDOCS_2_WARNING": "1",
                               "PATH": f"{DOCS_MKDOCS.parent}:/usr/bin:/bin"})
    assert done.returncode == 0, done.stderr[-4000:]
    return out


def _api_pages(site: Path) -> dict[str, str]:
    return {p.parent.name: p.read_text() for p in (site / "api").glob("*/index.html")}


def _text(fragment: str) -> str:
    return html.unescape(re.sub(r"<[^>]+>", "", fragment))


def test_the_api_reference_renders_sections_as_sections(site: Path) -> None:
    pages = _api_pages(site)
    assert len(pages) >= 14
    titles = [t for page in pages.values()
              for t in re.findall(r'class="doc-section-title">([^<]*)<', page)]
    for kind in ("Parameters:", "Returns:", "Raises:", "Attributes:"):
        assert titles.count(kind) >= 5, f"few {kind} sections: {titles.count(kind)}"
    run_on = [(name, m.group(1)[:80]) for name, page in pages.items()
              for m in re.finditer(r"<p>((?:Args|Returns|Raises|Attributes):.*?)</p>", page, re.S)]
    assert run_on == [], f"sections left as paragraphs: {run_on[:5]}"


def test_every_cross_reference_is_a_link_to_an_anchor_that_exists(site: Path) -> None:
    pages = _api_pages(site)
    literal = [(name, m.group(0)) for name, page in pages.items()
               for m in re.finditer(r"~usar_arm\.|:(?:class|mod|meth|func|attr|data|exc):`",
                                    _text(page))]
    assert literal == [], f"references shown as text: {literal[:5]}"
    anchors = {name: set(re.findall(r'id="([^"]+)"', page)) for name, page in pages.items()}
    links, broken = 0, []
    for name, page in pages.items():
        for href in re.findall(r'<a class="autorefs autorefs-internal"[^>]*href="([^"]+)"', page):
            links += 1
            where, _, anchor = href.partition("#")
            target = name if where in ("", "./") else Path(where).name or Path(where).parent.name
            if anchor not in anchors.get(target, set()):
                broken.append(f"{name}: {href}")
    assert links >= 100, f"only {links} cross-reference links"
    assert broken == [], f"links to no anchor: {broken[:10]}"


def test_no_signature_is_wider_than_the_page(site: Path) -> None:
    wide = []
    for name, page in _api_pages(site).items():
        for m in re.finditer(r'<div class="doc-signature[^"]*">(.*?)</div>', page, re.S):
            lines = _text(m.group(1)).splitlines()
            if lines and max(map(len, lines)) > SIGNATURE_COLUMNS:
                wide.append(f"{name}: {lines[0][:60]}")
    assert wide == [], f"{len(wide)} signatures wider than {SIGNATURE_COLUMNS} columns: {wide[:5]}"


@pytest.fixture(scope="module")
def served(site: Path) -> Iterator[str]:
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(site))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


@pytest.mark.parametrize("page", ["", "api/planning/", "api/arm/", "api/core/", "library/"])
def test_the_site_loads_in_a_browser_with_no_error(served: str, chromium: str,
                                                   page: str) -> None:
    with browser.Page.open() as tab:
        tab.goto(f"{served}/{page}")
        tab.pump(1.0)
        title = tab.evaluate("document.title")
        shown = tab.evaluate("document.querySelectorAll('a.autorefs').length")
        assert browser.page_errors(tab) == []
    assert "usar-arm" in title
    if page.startswith("api/"):
        assert shown > 0, f"{page}: no cross-reference links"
