"""Render pages of the built book in headless Chromium at a reader's width and check what a
reader sees: on the scorecard, every claim's verdict badge lies whole inside its column and
the page's content width; with ``--figures``, on every chapter, every figure's smallest
text is at least 8 pt at the size the figure is shown (its SVG's glyph scale times its
rendered over its own width).

    python tools/check_rendered.py _build/html [--width 1280] [--screenshot out.png] [--figures]

A copy of the page, with a script that measures it once loaded, is rendered with
``--dump-dom``; the measurements come back in the dumped DOM. Exits 1 naming what lies
outside, 2 if Chromium is missing (``apt-get install chromium``).
"""

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

FIGURES = """
<script>
window.addEventListener("load", () => {
  const imgs = [...document.querySelectorAll("article img")].map(
    (i) => ({src: i.getAttribute("src"), width: i.getBoundingClientRect().width}));
  const pre = document.createElement("pre");
  pre.id = "sgb-measure";
  pre.textContent = JSON.stringify(imgs);
  document.body.appendChild(pre);
});
</script>
"""
MIN_FONT_PT = 8.0
MEASURE = """
<script>
window.addEventListener("load", () => {
  const content = document.querySelector("article.bd-article") || document.querySelector("main");
  const table = document.querySelector("table.sgb-scorecard");
  const verdicts = [...document.querySelectorAll(
    "table.sgb-scorecard tr.sgb-claim td:last-child .sgb-badge")];
  const out = {
    viewport: window.innerWidth,
    content_right: content.getBoundingClientRect().right,
    table_right: table ? table.getBoundingClientRect().right : null,
    verdict_rights: verdicts.map((b) => b.getBoundingClientRect().right),
    cell_rights: verdicts.map((b) => b.parentElement.getBoundingClientRect().right),
  };
  const pre = document.createElement("pre");
  pre.id = "sgb-measure";
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>
"""


def chromium() -> str:
    """The Chromium executable on PATH."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        found = shutil.which(name)
        if found:
            return found
    raise FileNotFoundError("no Chromium on PATH: apt-get install chromium")


def _browser(*args: str) -> subprocess.CompletedProcess:
    command = [chromium(), "--headless=new", "--no-sandbox", "--disable-gpu", *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=120)


def measure(page: Path, width: int, script: str = MEASURE) -> dict | list:
    """Render ``page`` at ``width`` px with ``script`` and return what it measured (px)."""
    with tempfile.NamedTemporaryFile("w", suffix=".html", dir=page.parent, delete=False) as f:
        f.write(page.read_text().replace("</body>", script + "</body>"))
        probe = Path(f.name)
    try:
        done = _browser(
            f"--window-size={width},900",
            "--virtual-time-budget=10000",
            "--dump-dom",
            probe.as_uri(),
        )
    finally:
        probe.unlink()
    found = re.search(r'<pre id="sgb-measure"[^>]*>(.*?)</pre>', done.stdout, flags=re.S)
    if found is None:
        raise RuntimeError(f"the page reported no measurements: {done.stderr[-2000:]}")
    return json.loads(found.group(1).replace("&quot;", '"'))


def smallest_text(svg: Path, rendered_px: float) -> float | None:
    """The smallest text of a matplotlib SVG (glyphs drawn as paths at ``scale(size/100)``)
    in pt at ``rendered_px`` wide; ``None`` for an SVG with no text."""
    text = svg.read_text()
    scales = [float(x) for x in re.findall(r"scale\(([\d.]+) -[\d.]+\)", text)]
    width = re.search(r'width="([\d.]+)pt"', text)
    if not scales or width is None:
        return None
    natural_px = float(width.group(1)) * 96 / 72
    return min(scales) * 100 * min(1.0, rendered_px / natural_px)


def small_figures(html: Path, width: int) -> list[str]:
    """Every chapter figure whose smallest text is under ``MIN_FONT_PT`` as shown."""
    small = []
    for page in sorted((html / "book").glob("0*.html")):
        for image in measure(page.resolve(), width, FIGURES):
            svg = (page.parent / image["src"]).resolve()
            if svg.suffix != ".svg":
                continue
            size = smallest_text(svg, image["width"])
            if size is not None and size < MIN_FONT_PT - 0.05:
                small.append(f"{page.name}: {svg.name} shows text at {size:.1f} pt")
    return small


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("html", type=Path, help="the built book's html folder")
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--screenshot", type=Path, default=None)
    parser.add_argument(
        "--figures", action="store_true", help="also check every chapter figure's text size"
    )
    args = parser.parse_args(argv)
    page = (args.html / "book" / "scorecard.html").resolve()
    try:
        m = measure(page, args.width)
    except FileNotFoundError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    if args.screenshot is not None:
        _browser(
            f"--window-size={args.width},1400", f"--screenshot={args.screenshot}", page.as_uri()
        )
    limit = min(m["content_right"], m["viewport"])
    cells = m["cell_rights"]
    outside = [r for r, c in zip(m["verdict_rights"], cells, strict=True) if r > min(c, limit) + 1]
    print(
        f"{page} at {args.width} px: {len(m['verdict_rights'])} verdicts, the rightmost ends at "
        f"{max(m['verdict_rights'], default=0):.0f} px; the content ends at {limit:.0f} px"
    )
    if not m["verdict_rights"]:
        print("error: the scorecard has no claim lines", file=sys.stderr)
        return 1
    if outside:
        print(f"error: {len(outside)} verdicts end outside the content width", file=sys.stderr)
        return 1
    if not args.figures:
        return 0
    small = small_figures(args.html, args.width)
    for line in small:
        print(f"error: {line}, under {MIN_FONT_PT:g} pt", file=sys.stderr)
    print(f"figures: {len(small)} with text under {MIN_FONT_PT:g} pt as shown")
    return 1 if small else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
