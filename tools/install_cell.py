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

# Installed at the book's pins (requirements.txt): the JAX, Brax and MuJoCo stack. pip
# resolves what they need; every other package stays as the runtime has it.
STACK = ("jax", "jaxlib", "flax", "optax", "brax", "mujoco", "mujoco-mjx")

TEMPLATE = """\
# On Colab (or with SGB_WHEEL set, or a wheel of the book beside this notebook) install the
# sgb package: the wheel and requirements.txt downloaded from the book and uploaded next to
# the notebook if they are there, else the book's git ref. Only the JAX, Brax and MuJoCo
# stack is put at the book's pins; every other package stays as the runtime has it.
# Written by tools/install_cell.py from _config.yml.
import glob
import os
import shutil
import subprocess
import sys

REF = "{ref}"
PACKAGE = "{distribution} @ git+{url}@" + REF
PINS = "{raw}/" + REF + "/requirements.txt"
STACK = {stack}
UPLOADED = sorted(glob.glob("{wheel}-*.whl"))  # the newest last
if "google.colab" in sys.modules or "SGB_WHEEL" in os.environ or UPLOADED:
    import importlib
    import importlib.metadata as metadata
    import re
    import tempfile
    import time
    import urllib.request

    def name(text):
        return re.sub(r"[-_.]+", "-", text).lower()

    def installed():
        versions = {{}}
        for dist in metadata.distributions():  # the first on sys.path is the one imported
            versions.setdefault(name(dist.metadata["Name"]), dist.version)
        return versions

    local = os.path.exists("requirements.txt")
    package = os.environ.get("SGB_WHEEL", UPLOADED[-1] if UPLOADED else PACKAGE)
    source = os.environ.get("SGB_CONSTRAINTS", "requirements.txt" if local else PINS)
    try:
        if source.startswith(("https://", "http://")):
            with urllib.request.urlopen(source, timeout=60) as response:
                text = response.read().decode()
        else:
            with open(source) as file:
                text = file.read()
    except OSError as error:
        raise RuntimeError(
            f"cannot read the book's pins from {{source}} ({{error}}); "
            "upload requirements.txt from the book's page 'Run it yourself' next to this "
            "notebook, or point SGB_CONSTRAINTS at a copy of it"
        ) from error
    pins = [
        line.split("#")[0].strip()
        for line in text.splitlines()
        if "==" in line and name(line.split("==")[0].strip()) in STACK
    ]
    constraints = os.path.join(tempfile.mkdtemp(), "stack-pins.txt")
    with open(constraints, "w") as file:
        file.write("\\n".join(pins) + "\\n")
    # On a GPU, jax comes with its CUDA plugin at the pinned version (never a CPU-only jaxlib).
    gpu = ["jax[cuda12]"] if shutil.which("nvidia-smi") else []
    pip = [sys.executable, "-m", "pip", "install", "-q", package, *gpu, "-c", constraints]
    before = installed()
    done = subprocess.run(pip, capture_output=True, text=True)
    report = (done.stdout + done.stderr).strip()
    if done.returncode != 0:
        raise RuntimeError(
            f"installing {{package}} failed (pip exit status {{done.returncode}}) in\\n"
            f"  {{' '.join(pip)}}\\n{{report[-4000:]}}\\n(until the book's repository is public, "
            "upload the wheel and requirements.txt from the book's page 'Run it yourself' "
            "next to this notebook and run it again)"
        )
    if "ERROR" in report or "conflict" in report:
        print("pip reports:\\n" + report[-4000:])
    importlib.invalidate_caches()
    after = installed()
    moved = {{n: (before[n], v) for n, v in after.items() if n in before and before[n] != v}}
    added = sorted(n for n in after if n not in before)
    if moved or added:
        changes = ", ".join(f"{{n}} {{a}} -> {{b}}" for n, (a, b) in sorted(moved.items()))
        print(f"pip changed {{len(moved)}} packages ({{changes or 'none'}}), added {{len(added)}}")
    owners = metadata.packages_distributions()
    imported = {{module.partition(".")[0] for module in list(sys.modules)}}
    stale = sorted({{name(d) for m in imported for d in owners.get(m, []) if name(d) in moved}})
    if stale:
        changes = ", ".join(f"{{n}} {{moved[n][0]}} -> {{moved[n][1]}}" for n in stale)
        message = f"pip changed packages this session had already imported: {{changes}}. "
        if "google.colab" in sys.modules:
            print(
                message + "Restarting the session now (what Runtime > Restart session does); "
                "when it is back, run the notebook again (Runtime > Run all): this cell then "
                "finds everything installed and goes on.",
                flush=True,
            )
            time.sleep(1)
            os.kill(os.getpid(), 9)
        raise RuntimeError(message + "Restart the kernel and run the notebook again.")
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
    return TEMPLATE.format(
        ref=ref,
        distribution=DISTRIBUTION,
        url=url,
        raw=raw,
        stack=_tuple(STACK),
        wheel=DISTRIBUTION.replace("-", "_"),
    ).rstrip("\n")


def _tuple(names: tuple[str, ...]) -> str:
    """``names`` as a tuple literal the way ruff formats it."""
    return "(" + ", ".join(f'"{n}"' for n in names) + ")"


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
