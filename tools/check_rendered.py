"""Render pages of the built book in headless Chromium at a reader's width and check what a
reader sees: on the scorecard, every claim's verdict badge lies whole inside its column and
the page's content width.

    python tools/check_rendered.py _build/html [--width 1280] [--screenshot out.png]

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


def measure(page: Path, width: int) -> dict:
    """Render ``page`` at ``width`` px and return the scorecard's measurements (px)."""
    with tempfile.NamedTemporaryFile("w", suffix=".html", dir=page.parent, delete=False) as f:
        f.write(page.read_text().replace("</body>", MEASURE + "</body>"))
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


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("html", type=Path, help="the built book's html folder")
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--screenshot", type=Path, default=None)
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
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
