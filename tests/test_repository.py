"""Checks of the repository itself: pins, notebooks as committed, the Colab install cell."""

import importlib.util
import json
import os
import re
import subprocess
import sys
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
_spec = importlib.util.spec_from_file_location("install_cell", ROOT / "tools" / "install_cell.py")
install_cell = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(install_cell)
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
def test_notebook_starts_with_the_install_cell_of_the_configured_ref(notebook):
    code_cells = [c for c in _load(notebook)["cells"] if c["cell_type"] == "code"]
    assert code_cells, f"{notebook} has no code cell"
    first = code_cells[0]
    assert "remove-cell" in first.get("metadata", {}).get("tags", []), (
        f"{notebook}: the install cell must be tagged remove-cell"
    )
    assert _source(first) == install_cell.cell_source(), (
        f"{notebook}: install cell differs from _config.yml's; run python tools/install_cell.py"
    )


def test_install_cell_installs_the_launch_buttons_ref_with_the_pins():
    url, ref = install_cell.repository()
    source = install_cell.cell_source()
    assert f'REF = "{ref}"' in source
    assert f"sgb-companion @ git+{url}@" in source
    assert "/requirements.txt" in source and '"-c", pins' in source


def _run_install_cell(tmp_path: Path, prelude: str, **env: str) -> subprocess.CompletedProcess:
    script = tmp_path / "cell.py"
    script.write_text(prelude + install_cell.cell_source() + "\n")
    environment = {k: v for k, v in os.environ.items() if not k.startswith("SGB_")} | env
    return subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, env=environment
    )


def test_a_failed_install_raises(tmp_path):
    missing = tmp_path / "sgb_companion-0.0.0-py3-none-any.whl"
    done = _run_install_cell(tmp_path, "", SGB_WHEEL=str(missing))
    assert done.returncode != 0
    assert "RuntimeError: installing " + str(missing) + " failed" in done.stderr


def test_on_a_gpu_the_install_adds_jax_with_its_cuda_plugin(tmp_path):
    fake = tmp_path / "bin"
    fake.mkdir()
    (fake / "nvidia-smi").write_text("#!/bin/sh\nexit 0\n")
    (fake / "nvidia-smi").chmod(0o755)
    missing = tmp_path / "sgb_companion-0.0.0-py3-none-any.whl"
    path = f"{fake}{os.pathsep}{os.environ['PATH']}"
    done = _run_install_cell(tmp_path, "", SGB_WHEEL=str(missing), PATH=path)
    assert "RuntimeError: installing" in done.stderr
    assert f"install -q {missing} jax[cuda12] -c " in done.stderr


def test_a_failed_import_raises(tmp_path):
    done = _run_install_cell(tmp_path, "import sys\nsys.modules['sgb'] = None\n")
    assert done.returncode != 0
    assert "RuntimeError: the sgb package is not importable" in done.stderr


def test_the_wheel_lists_every_package_and_carries_the_committed_results():
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    subpackages = {
        ".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "sgb").rglob("__init__.py")
    }
    assert subpackages | {"sgb.results"} == set(setuptools["packages"])
    assert setuptools["package-dir"] == {"sgb.results": "results"}
    patterns = setuptools["package-data"]["sgb.results"]
    committed = subprocess.run(
        ["git", "ls-files", "results"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    for path in committed:
        inside = Path(path).relative_to("results")
        assert any(inside.match(p) and len(inside.parts) == len(Path(p).parts) for p in patterns), (
            f"{path} is committed but not shipped in the wheel"
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


def test_figures_are_named_once_and_captioned():
    names = []
    for notebook in NOTEBOOKS:
        for cell in _load(notebook)["cells"]:
            figure = cell.get("metadata", {}).get("mystnb", {}).get("figure")
            if figure:
                assert figure.get("caption"), f"{notebook}: figure {figure} has no caption"
                assert figure.get("name", "").startswith("fig-"), f"{notebook}: {figure}"
                names.append(figure["name"])
    assert len(names) >= 19 and len(names) == len(set(names))


def test_licence_and_citation_agree_with_the_package():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    version = re.search(r'__version__ = "(.+)"', (ROOT / "sgb" / "__init__.py").read_text())
    assert project["license"]["text"] == citation["license"] == "MIT"
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    assert citation["version"] == version.group(1)
    assert citation["repository-code"] == install_cell.repository()[0]


def test_the_bibliography_holds_the_paper_under_its_own_title():
    bib = (ROOT / "references.bib").read_text()
    paper = re.search(r"@misc\{paper,(.*?)\n\}", bib, re.DOTALL).group(1)
    title = "Stochastic Wiring of Cell Types Enhances Fitness by Generating Phenotypic Variability"
    assert title in paper
