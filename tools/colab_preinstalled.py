"""Write .ci/colab-preinstalled.txt: Colab's versions of the packages the book installs.

    python tools/colab_preinstalled.py PIP_FREEZE COMMIT DATE PYTHON

PIP_FREEZE is googlecolab/backend-info's ``pip-freeze.txt`` at COMMIT (of DATE, with
``os-info.txt`` naming PYTHON). The packages kept are those of ``sgb-companion``'s
dependency tree in this environment (its requirements, theirs, and so on, with markers
evaluated for PYTHON on Linux) that Colab preinstalls, at Colab's versions. .ci/colab_like
seeds its venv with them, so that the install cell meets what a Colab reader's runtime has.
"""

import importlib.metadata
import re
import sys
from pathlib import Path

from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / ".ci" / "colab-preinstalled.txt"


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


def main(freeze: Path, commit: str, date: str, python: str) -> None:
    colab = {}
    for line in freeze.read_text().splitlines():
        match = re.match(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==(\S+)$", line.strip())
        if match:
            colab[_name(match.group(1))] = match.group(2)
    ours = sorted(dependency_tree("sgb-companion", python) & set(colab))
    header = [
        "# Colab's preinstalled versions of the packages the book installs (the dependency tree",
        "# of sgb-companion), from googlecolab/backend-info's pip-freeze.txt",
        f"# at commit {commit} ({date}; os-info.txt: Python {python}).",
        "# .ci/colab_like seeds its venv with them before the install cell runs.",
        "# Written by tools/colab_preinstalled.py; rerun it on a newer pip-freeze.txt.",
    ]
    OUT.write_text("\n".join(header + [f"{n}=={colab[n]}" for n in ours]) + "\n")


if __name__ == "__main__":
    main(Path(sys.argv[1]), *sys.argv[2:5])
