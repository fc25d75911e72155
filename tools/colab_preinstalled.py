"""Write .ci/colab-preinstalled.txt: Colab's versions of the packages the book installs.

    python tools/colab_preinstalled.py PIP_FREEZE COMMIT DATE PYTHON
    python tools/colab_preinstalled.py --gpu PIP_FREEZE_GPU COMMIT DATE PYTHON

PIP_FREEZE is googlecolab/backend-info's ``pip-freeze.txt`` at COMMIT (of DATE, with
``os-info.txt`` naming PYTHON). The packages kept are those of ``sgb-companion``'s
dependency tree in this environment (its requirements, theirs, and so on, with markers
evaluated for PYTHON on Linux) that Colab preinstalls, at Colab's versions. .ci/colab_like
seeds its venv with them, so that the install cell meets what a Colab reader's runtime has.

With ``--gpu``, PIP_FREEZE_GPU is ``pip-freeze.gpu.txt`` (and ``os-info-gpu.txt`` names
PYTHON), the output is .ci/colab-preinstalled-gpu.txt, and the tree also holds what the
install cell's GPU branch asks for, ``jax[cuda12]`` at the jax installed here (the CUDA
plugin, its PJRT and the nvidia-* wheels): pip resolves it (``--dry-run``, for the Python
running this script) since the plugin is not installed here. .ci/colab_gpu_resolve reads it.
"""

import importlib.metadata
import json
import re
import subprocess
import sys
from pathlib import Path

from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / ".ci" / "colab-preinstalled.txt"
OUT_GPU = ROOT / ".ci" / "colab-preinstalled-gpu.txt"
USE = "# .ci/colab_like seeds its venv with them before the install cell runs."
USE_GPU = "# .ci/colab_gpu_resolve resolves the install cell's GPU branch against them."


def _name(text: str) -> str:
    return re.sub(r"[-_.]+", "-", text).lower()


def dependency_tree(root: str, python: str) -> set[str]:
    """Normalised names of ``root`` and everything it requires, as installed here."""
    environment = {"python_version": ".".join(python.split(".")[:2]), "python_full_version": python}
    environment |= {"sys_platform": "linux", "platform_system": "Linux", "extra": ""}
    seen, todo = set(), [root]
    while todo:
        name = _name(todo.pop())
        if name in seen:
            continue
        seen.add(name)
        try:
            requires = importlib.metadata.distribution(name).requires or []
        except importlib.metadata.PackageNotFoundError:
            continue
        for line in requires:
            requirement = Requirement(line)
            if requirement.marker is None or requirement.marker.evaluate(environment):
                todo.append(requirement.name)
    return seen - {_name(root)}


def cuda_tree() -> set[str]:
    """Normalised names of what ``jax[cuda12]`` at the installed jax resolves to (pip)."""
    wanted = f"jax[cuda12]=={importlib.metadata.version('jax')}"
    pip = [sys.executable, "-m", "pip", "install", "--dry-run", "--ignore-installed", "-q"]
    done = subprocess.run([*pip, "--report", "-", wanted], capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"pip cannot resolve {wanted}:\n{done.stderr[-4000:]}")
    return {_name(item["metadata"]["name"]) for item in json.loads(done.stdout)["install"]}


def main(freeze: Path, commit: str, date: str, python: str, gpu: bool = False) -> None:
    colab = {}
    for line in freeze.read_text().splitlines():
        match = re.match(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==(\S+)$", line.strip())
        if match:
            colab[_name(match.group(1))] = match.group(2)
    tree = dependency_tree("sgb-companion", python) | (cuda_tree() if gpu else set())
    ours = sorted(tree & set(colab))
    freeze_name, os_info, extra, use = (
        ("pip-freeze.gpu.txt", "os-info-gpu.txt", " and of jax[cuda12]", USE_GPU)
        if gpu
        else ("pip-freeze.txt", "os-info.txt", "", USE)
    )
    header = [
        "# Colab's preinstalled versions of the packages the book installs (the dependency tree",
        f"# of sgb-companion{extra}), from googlecolab/backend-info's {freeze_name}",
        f"# at commit {commit} ({date}; {os_info}: Python {python}).",
        use,
        f"# Written by tools/colab_preinstalled.py; rerun it on a newer {freeze_name}.",
    ]
    out = OUT_GPU if gpu else OUT
    out.write_text("\n".join(header + [f"{n}=={colab[n]}" for n in ours]) + "\n")


if __name__ == "__main__":
    gpu = sys.argv[1] == "--gpu"
    main(Path(sys.argv[1 + gpu]), *sys.argv[2 + gpu : 5 + gpu], gpu=gpu)
