"""Render an HTML report in a real headless browser and measure whether anything runs off
a 1280 px page (issue #19: wide tables scroll inside the page, figures fit).

The browser is Chromium (``PNEUMACT_TEST_BROWSER``, else ``chromium``, ``chromium-browser``,
``google-chrome`` on the PATH). A script added to a copy of the page measures, once it is
laid out, the document's scroll width against the viewport, every element whose right edge
passes the viewport (outside a table's own scroll box) and every image wider than its
container, and writes the result into the DOM, which ``--dump-dom`` returns.
"""

from __future__ import annotations

import html
import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

WIDTH = 1280  # px: a laptop browser window
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run",
         "--hide-scrollbars", f"--window-size={WIDTH},900", "--virtual-time-budget=10000")
NAMES = ("chromium", "chromium-browser", "google-chrome")
MEASURE = """<script>
window.addEventListener("load", () => {
  const view = document.documentElement.clientWidth;
  const past = [];
  for (const el of document.querySelectorAll("body *")) {
    if (el.parentElement && el.parentElement.closest(".table-wrap")) continue;
    const box = el.getBoundingClientRect();
    if (box.width > 0 && box.right > view + 0.5) past.push(el.tagName.toLowerCase());
  }
  const images = [...document.images].filter(
    img => img.getBoundingClientRect().width > img.parentElement.clientWidth + 0.5).length;
  const out = document.createElement("pre");
  out.id = "layout-check";
  out.textContent = JSON.stringify({view, scrollWidth: document.documentElement.scrollWidth,
    past: past.slice(0, 20), overflowing: past.length, images,
    tables: document.querySelectorAll("table").length,
    wrapped: document.querySelectorAll(".table-wrap > table").length,
    figures: document.images.length});
  document.body.appendChild(out);
});
</script>"""


def browser() -> str | None:
    """The headless browser to use, or None."""
    given = os.environ.get("PNEUMACT_TEST_BROWSER")
    if given:
        return shutil.which(given) or (given if Path(given).exists() else None)
    return next((found for name in NAMES if (found := shutil.which(name))), None)


SKIP_REASON = ("no headless browser found (set PNEUMACT_TEST_BROWSER or install chromium, "
               "e.g. apt-get install chromium): the report layout is only checked in a "
               "real browser")
needs_browser = pytest.mark.skipif(browser() is None, reason=SKIP_REASON)


def layout(report: Path) -> dict:
    """The measurements of ``report`` rendered at 1280 px."""
    program = browser()
    if program is None:
        pytest.skip(SKIP_REASON)
    with tempfile.TemporaryDirectory() as folder:
        page = Path(folder) / "page.html"
        text = Path(report).read_text(encoding="utf-8")
        page.write_text(text.replace("</body>", MEASURE + "</body>"), encoding="utf-8")
        run = subprocess.run([program, *FLAGS, f"--user-data-dir={folder}/profile",
                              "--dump-dom", page.as_uri()], capture_output=True, text=True,
                             timeout=120, check=False)
    start = run.stdout.find('<pre id="layout-check">')
    if start < 0:
        raise AssertionError(f"the browser returned no measurement (exit {run.returncode}): "
                             f"{run.stderr[-2000:]}")
    body = run.stdout[start + len('<pre id="layout-check">'):]
    return json.loads(html.unescape(body[:body.index("</pre>")]))


def assert_fits_the_page(report: Path) -> dict:
    """Nothing of ``report`` runs off a 1280 px page; every table sits in its scroll box."""
    found = layout(report)
    assert found["view"] >= WIDTH - 20, found  # the window was 1280 px wide
    assert found["scrollWidth"] <= found["view"], found
    assert found["overflowing"] == 0, found
    assert found["images"] == 0, found
    assert found["wrapped"] == found["tables"], found
    return found
