"""Checks of the repository itself: pins, notebooks as committed, the Colab install cell."""

import json
import re
import tomllib
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted(
    p.relative_to(ROOT).as_posix()
    for p in (ROOT / "book").rglob("*.ipynb")
    if ".ipynb_checkpoints" not in p.parts
)
INSTALL_URL = "https://github.com/sgb-companion/sgb-book"
PIN = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==(\S+)$")


def _normalise(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _pins(lines: list[str]) -> dict[str, str]:
    """``name==version`` lines as {normalised name: version}; other lines are ignored."""
    pins = {}
    for line in lines:
        match = PIN.match(line.split("#", 1)[0].strip())
        if match:
            name = _normalise(match.group(1))
            assert name not in pins, f"{name} is pinned twice"
            pins[name] = match.group(2)
    return pins


def _load(notebook: str) -> dict:
    return json.loads((ROOT / notebook).read_text())


def _source(cell: dict) -> str:
    source = cell["source"]
    return source if isinstance(source, str) else "".join(source)


def test_requirements_and_environment_pin_the_same_versions():
    requirements = _pins((ROOT / "requirements.txt").read_text().splitlines())
    environment = yaml.safe_load((ROOT / "environment.yml").read_text())
    pip_sections = [
        dep["pip"] for dep in environment["dependencies"] if isinstance(dep, dict) and "pip" in dep
    ]
    assert len(pip_sections) == 1, "environment.yml needs exactly one pip: section"
    conda_pins = _pins([str(dep) for dep in pip_sections[0]])
    assert requirements, "requirements.txt pins nothing"
    assert conda_pins == requirements


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_notebook_is_committed_without_outputs(notebook):
    for index, cell in enumerate(_load(notebook)["cells"]):
        if cell["cell_type"] != "code":
            continue
        assert cell.get("outputs") == [], f"{notebook}: cell {index} has outputs"
        assert cell.get("execution_count") is None, f"{notebook}: cell {index} has a count"


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_notebook_starts_with_the_guarded_install_cell(notebook):
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    code_cells = [c for c in _load(notebook)["cells"] if c["cell_type"] == "code"]
    assert code_cells, f"{notebook} has no code cell"
    first = code_cells[0]
    source = _source(first)
    assert "remove-cell" in first.get("metadata", {}).get("tags", []), (
        f"{notebook}: the install cell must be tagged remove-cell"
    )
    assert re.search(r'^if "google\.colab" in sys\.modules:', source, re.MULTILINE), (
        f"{notebook}: the install must be guarded to run on Colab only"
    )
    match = re.search(
        r'^\s+%pip install -q "sgb @ git\+' + re.escape(INSTALL_URL) + r'@(\S+)"\s*$',
        source,
        re.MULTILINE,
    )
    assert match, f"{notebook}: no pinned `%pip install` of sgb inside the guard"
    assert match.group(1) == f"v{version}", (
        f"{notebook} installs {match.group(1)}, pyproject.toml says v{version}"
    )


def test_pinned_versions_satisfy_the_package_dependencies():
    from packaging.requirements import Requirement

    requirements = _pins((ROOT / "requirements.txt").read_text().splitlines())
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    declared = list(project["dependencies"])
    for extra in project["optional-dependencies"].values():
        declared += extra
    for line in declared:
        requirement = Requirement(line)
        name = _normalise(requirement.name)
        assert name in requirements, f"{name} is a dependency but requirements.txt does not pin it"
        assert requirements[name] in requirement.specifier, (
            f"requirements.txt pins {name}=={requirements[name]}, outside {requirement.specifier}"
        )
