"""The first cell of every chapter: on Colab, install ``sgb`` from the book's own git ref.

The repository and the ref come from ``_config.yml`` (``repository.url`` and
``repository.branch``, which the launch buttons open too). After changing them, run
``python tools/install_cell.py`` to rewrite the cell in every notebook;
tests/test_repository.py checks that every notebook holds the cell this script writes.
"""

import sys
from pathlib import Path

import nbformat
import yaml

ROOT = Path(__file__).resolve().parent.parent
DISTRIBUTION = "sgb-companion"

TEMPLATE = """\
# On Colab (or with SGB_WHEEL set) install the sgb package of this book's git ref, under
# the book's pinned versions. Written by tools/install_cell.py from _config.yml.
import os
import shutil
import subprocess
import sys

REF = "{ref}"
PACKAGE = "{distribution} @ git+{url}@" + REF
PINS = "{raw}/" + REF + "/requirements.txt"
if "google.colab" in sys.modules or "SGB_WHEEL" in os.environ:
    package = os.environ.get("SGB_WHEEL", PACKAGE)
    # On a GPU, jax comes with its CUDA plugin at the pinned version (never a CPU-only jaxlib).
    gpu = ["jax[cuda12]"] if shutil.which("nvidia-smi") else []
    pins = os.environ.get("SGB_CONSTRAINTS", PINS)
    pip = [sys.executable, "-m", "pip", "install", "-q", package, *gpu, "-c", pins]
    done = subprocess.run(pip, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(
            f"installing {{package}} failed (pip exit status {{done.returncode}}) in\\n"
            f"  {{' '.join(pip)}}\\n" + done.stderr[-3000:]
        )
try:
    import sgb  # noqa: F401 (fails here, not a cell later)
except ImportError as error:
    raise RuntimeError(
        "the sgb package is not importable: on Colab the cell above installs it; "
        "elsewhere create the book's environment first (see the README)"
    ) from error
"""


def repository() -> tuple[str, str]:
    """(repository URL, git ref) of the book, from ``_config.yml``."""
    config = yaml.safe_load((ROOT / "_config.yml").read_text())["repository"]
    return config["url"].rstrip("/"), config["branch"]


def cell_source() -> str:
    """The install cell's source for the repository and ref of ``_config.yml``."""
    url, ref = repository()
    if not url.startswith("https://github.com/"):
        raise ValueError(f"repository.url must be a GitHub URL, got {url!r}")
    raw = url.replace("https://github.com/", "https://raw.githubusercontent.com/", 1)
    return TEMPLATE.format(ref=ref, distribution=DISTRIBUTION, url=url, raw=raw).rstrip("\n")


def notebooks() -> list[Path]:
    """Every chapter notebook of the book."""
    return sorted(p for p in (ROOT / "book").glob("*.ipynb"))


def write(path: Path) -> None:
    """Make the first code cell of ``path`` the install cell, tagged ``remove-cell``."""
    notebook = nbformat.read(path, as_version=4)
    first = next(c for c in notebook.cells if c.cell_type == "code")
    first.source = cell_source()
    first.metadata["tags"] = ["remove-cell"]
    nbformat.write(notebook, path)


if __name__ == "__main__":
    for path in notebooks():
        write(path)
    sys.exit(0)
