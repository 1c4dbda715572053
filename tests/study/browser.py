"""Measure a page's layout in headless Chromium: which tables or images overflow the page.

The page is copied with a small script added that, after loading, opens every ``<details>``,
then lists every table that is wider than the page's content box without sitting in a box that
scrolls sideways, every image wider than the window, and whether the page itself scrolls
sideways (``problems``), and, with the section it is in, every table whose box does scroll
sideways (``scrolled``). Chromium prints the resulting DOM (``--dump-dom``) and the list is
read back from it.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

BROWSERS = ("chromium", "chromium-browser", "google-chrome")

_PROBE = """
<script>
window.addEventListener("load", () => {
  document.querySelectorAll("details").forEach(d => { d.open = true; });
  const bad = [];
  const doc = document.documentElement;
  if (doc.scrollWidth > doc.clientWidth + 1) {
    bad.push(`page scrolls sideways: ${doc.scrollWidth} px > ${doc.clientWidth} px`);
  }
  const body = document.body.getBoundingClientRect();
  const scrolls = el => ["auto", "scroll"].includes(getComputedStyle(el).overflowX);
  document.querySelectorAll("table").forEach((t, k) => {
    let p = t.parentElement;
    while (p && p !== document.body && !scrolls(p)) p = p.parentElement;
    const r = t.getBoundingClientRect();
    if ((!p || p === document.body) && r.right > body.right + 1) {
      const head = (t.querySelector("th") || t).textContent.slice(0, 40);
      const w = Math.round(r.width), content = Math.round(body.width);
      bad.push(`table ${k} ("${head}") is ${w} px wide, page content ${content} px`);
    }
    if (p && p !== document.body && p.getBoundingClientRect().right > body.right + 1) {
      bad.push(`scroll box of table ${k} is wider than the page`);
    }
  });
  document.querySelectorAll("img").forEach((im, k) => {
    if (im.getBoundingClientRect().right > doc.clientWidth + 1) {
      bad.push(`image ${k} is wider than the window`);
    }
  });
  // tables whose box scrolls sideways, with the section (the h2 above) they are in
  const scrolled = [];
  const heads = [...document.querySelectorAll("h2")];
  document.querySelectorAll("table").forEach((t, k) => {
    const p = t.parentElement;
    if (p && p !== document.body && scrolls(p) && p.scrollWidth > p.clientWidth + 1) {
      const before = Node.DOCUMENT_POSITION_FOLLOWING;
      const above = heads.filter(h => h.compareDocumentPosition(t) & before);
      const section = above.length ? above[above.length - 1].textContent : "";
      const size = `${p.scrollWidth} px in ${p.clientWidth} px`;
      scrolled.push(`${section}: table ${k} scrolls sideways (${size})`);
    }
  });
  const out = document.createElement("pre");
  out.id = "layout-probe";
  const tables = document.querySelectorAll("table").length;
  out.textContent = JSON.stringify({tables: tables, problems: bad, scrolled: scrolled});
  document.body.appendChild(out);
});
</script>
"""


def find_browser() -> str | None:
    """Path of a Chromium-like browser, or None."""
    return next((shutil.which(b) for b in BROWSERS if shutil.which(b)), None)


def layout_problems(html_file: Path, width: int, browser: str, workdir: Path) -> dict:
    """Render ``html_file`` in a window ``width`` px wide.

    Returns ``{"tables": n, "problems": [...], "scrolled": ["<section>: table k scrolls ...",
    ...]}``.
    """
    text = html_file.read_text(encoding="utf-8")
    probe = workdir / f"probe-{width}-{html_file.name}"
    probe.write_text(text.replace("</body>", _PROBE + "</body>"), encoding="utf-8")
    proc = subprocess.run(
        [
            browser,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            f"--window-size={width},1200",
            "--virtual-time-budget=5000",
            "--dump-dom",
            probe.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=180,
        check=False,
    )
    m = re.search(r'<pre id="layout-probe">(.*?)</pre>', proc.stdout, re.DOTALL)
    if m is None:
        raise RuntimeError(
            f"the layout probe did not run (exit {proc.returncode}): {proc.stderr[-500:]}"
        )
    return json.loads(
        m.group(1)
        .replace("&quot;", '"')
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
    )
