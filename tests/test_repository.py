"""Checks of the repository itself: pins, notebooks as committed, the Colab install cell."""

import importlib.util
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tomllib
import warnings
from pathlib import Path

import nbformat
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
        assert "execution" not in cell["metadata"], f"{notebook}: cell {index} has run times"


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_notebook_validates_with_an_id_on_every_cell(notebook):
    """nbformat 4.5 requires cell ids; a missing one is a warning today, an error later."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        book = nbformat.read(ROOT / notebook, as_version=4)
        nbformat.validate(book)
    ids = [cell.get("id") for cell in book.cells]
    assert None not in ids, f"{notebook}: a cell has no id"
    assert len(set(ids)) == len(ids), f"{notebook}: two cells share an id"


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
    assert "/requirements.txt" in source and '"-c", constraints' in source


def test_the_install_cell_pins_only_the_stack_and_requirements_pin_all_of_it():
    requirements = _pins((ROOT / "requirements.txt").read_text().splitlines())
    stack = {_normalise(name) for name in install_cell.STACK}
    assert stack <= set(requirements), f"unpinned: {sorted(stack - set(requirements))}"
    assert {"numpy", "pandas", "scipy", "matplotlib", "scikit-learn"}.isdisjoint(stack)


def _run_install_cell(
    tmp_path: Path, prelude: str, pythonpath: list[Path] = (), **env: str
) -> subprocess.CompletedProcess:
    script = tmp_path / "cell.py"
    script.write_text(prelude + install_cell.cell_source() + "\n")
    environment = {k: v for k, v in os.environ.items() if not k.startswith("SGB_")}
    environment["SGB_CONSTRAINTS"] = str(ROOT / "requirements.txt")
    if pythonpath:
        paths = [str(p) for p in pythonpath] + [environment.get("PYTHONPATH", "")]
        environment["PYTHONPATH"] = os.pathsep.join(p for p in paths if p)
    return subprocess.run(
        [sys.executable, str(script)],
        capture_output=True,
        text=True,
        env={k: v for k, v in (environment | env).items() if v != ""},  # "": unset it
        cwd=tmp_path,
    )


def _distribution(site: Path, name: str, version: str) -> None:
    """Make ``site`` hold the distribution ``name`` at ``version``: a module and its
    metadata, as pip leaves them."""
    (site / name).mkdir(parents=True, exist_ok=True)
    (site / name / "__init__.py").write_text(f'version = "{version}"\n')
    for old in site.glob(f"{name}-*.dist-info"):
        shutil.rmtree(old)
    info = site / f"{name}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n")
    (info / "top_level.txt").write_text(f"{name}\n")


# A stand-in for pip, found first on PYTHONPATH by the cell's `python -m pip`: it keeps the
# command line and the constraints it was given, moves the distribution `sgbfake` to
# version 2.0 (what pip does to a package it upgrades) and prints what FAKE_PIP_SAYS.
_FAKE_PIP = """\
import os, shutil, sys
from pathlib import Path
out = Path(os.environ["FAKE_PIP_LOG"])
(out / "argv.txt").write_text(" ".join(sys.argv[1:]))
constraints = sys.argv[sys.argv.index("-c") + 1]
shutil.copy(constraints, out / "constraints.txt")
site = Path(os.environ["FAKE_SITE"])
for old in site.glob("sgbfake-*.dist-info"):
    shutil.rmtree(old)
info = site / "sgbfake-2.0.dist-info"
info.mkdir()
(info / "METADATA").write_text("Metadata-Version: 2.1\\nName: sgbfake\\nVersion: 2.0\\n")
(info / "top_level.txt").write_text("sgbfake\\n")
print(os.environ.get("FAKE_PIP_SAYS", ""), file=sys.stderr)
"""


def _run_with_fake_pip(tmp_path: Path, prelude: str, **env: str) -> subprocess.CompletedProcess:
    fake, site, log = tmp_path / "fake_pip", tmp_path / "site", tmp_path / "log"
    (fake / "pip").mkdir(parents=True)
    (fake / "pip" / "__init__.py").write_text("")
    (fake / "pip" / "__main__.py").write_text(_FAKE_PIP)
    log.mkdir()
    _distribution(site, "sgbfake", "1.0")
    wheel = tmp_path / "sgb_companion-0.1.0-py3-none-any.whl"
    settings = {"SGB_WHEEL": str(wheel), "FAKE_PIP_LOG": str(log), "FAKE_SITE": str(site)}
    return _run_install_cell(tmp_path, prelude, [fake, site], **(settings | env))


def test_the_install_cell_finds_a_wheel_and_pins_uploaded_beside_the_notebook(tmp_path):
    """No SGB_* variable: the newest wheel of the book and requirements.txt in the working
    directory (Colab's /content) are what it installs and pins from."""
    for version in ("0.0.9", "0.1.0"):
        (tmp_path / f"sgb_companion-{version}-py3-none-any.whl").write_bytes(b"")
    pins = (ROOT / "requirements.txt").read_text()
    (tmp_path / "requirements.txt").write_text(re.sub(r"(?m)^jax==\S+", "jax==0.0.1", pins))
    done = _run_with_fake_pip(tmp_path, "", SGB_WHEEL="", SGB_CONSTRAINTS="")
    assert done.returncode == 0, done.stderr
    argv = (tmp_path / "log" / "argv.txt").read_text()
    assert argv.startswith("install -q sgb_companion-0.1.0-py3-none-any.whl ")
    constraints = (tmp_path / "log" / "constraints.txt").read_text().splitlines()
    assert "jax==0.0.1" in constraints


def test_the_install_cell_constrains_only_the_stack_and_reports_what_pip_changed(tmp_path):
    done = _run_with_fake_pip(tmp_path, "")
    assert done.returncode == 0, done.stderr
    argv = (tmp_path / "log" / "argv.txt").read_text()
    assert argv.startswith(f"install -q {tmp_path / 'sgb_companion-0.1.0-py3-none-any.whl'} ")
    constraints = _pins((tmp_path / "log" / "constraints.txt").read_text().splitlines())
    requirements = _pins((ROOT / "requirements.txt").read_text().splitlines())
    assert constraints == {_normalise(n): requirements[_normalise(n)] for n in install_cell.STACK}
    # sgbfake moved, but nothing had imported it: no restart
    assert "pip changed 1 packages (sgbfake 1.0 -> 2.0)" in done.stdout
    assert "restart" not in (done.stdout + done.stderr).lower()


def test_the_install_cell_shows_a_conflict_report(tmp_path):
    says = "ERROR: pip's dependency resolver ... the following dependency conflicts."
    done = _run_with_fake_pip(tmp_path, "", FAKE_PIP_SAYS=says)
    assert done.returncode == 0, done.stderr
    assert "pip reports:\n" + says in done.stdout


def test_a_changed_imported_package_stops_the_cell_with_a_restart_notice(tmp_path):
    done = _run_with_fake_pip(tmp_path, "import sgbfake\n")
    assert done.returncode != 0
    assert "already imported: sgbfake 1.0 -> 2.0" in done.stderr
    assert "Restart the kernel and run the notebook again" in done.stderr


def test_on_colab_a_changed_imported_package_restarts_the_session(tmp_path):
    colab = "import sys, types\nsys.modules['google.colab'] = types.ModuleType('google.colab')\n"
    done = _run_with_fake_pip(tmp_path, colab + "import sgbfake\n")
    assert done.returncode == -signal.SIGKILL  # what Colab takes as a restart of the session
    assert "already imported: sgbfake 1.0 -> 2.0" in done.stdout
    assert "Restarting the session now (what Runtime > Restart session does)" in done.stdout


def test_unreadable_pins_raise(tmp_path):
    missing = tmp_path / "sgb_companion-0.0.0-py3-none-any.whl"
    done = _run_install_cell(
        tmp_path, "", SGB_WHEEL=str(missing), SGB_CONSTRAINTS=str(tmp_path / "none.txt")
    )
    assert done.returncode != 0
    assert "cannot read the book's pins from" in done.stderr and "SGB_CONSTRAINTS" in done.stderr


def test_a_failed_install_raises(tmp_path):
    missing = tmp_path / "sgb_companion-0.0.0-py3-none-any.whl"
    done = _run_install_cell(tmp_path, "", SGB_WHEEL=str(missing))
    assert done.returncode != 0
    assert "RuntimeError: installing " + str(missing) + " failed" in done.stderr
    assert "'Run it yourself'" in done.stderr


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
        if path.endswith(".state.npz"):
            continue  # an unfinished run's state, kept so a clone resumes it (sgb.grid)
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


PAPER_TITLE = (
    "Stochastic Wiring of Cell Types Enhances Fitness by Generating Phenotypic Variability"
)
PAPER_DOI = "10.1101/2024.08.07.606541"
PAPER_AUTHORS = ["Lachi", "Huang", "Mavor-Parker", "Ghosh", "Richards", "Zador"]


def test_the_bibliography_cites_the_paper_with_its_authors_and_doi():
    bib = (ROOT / "references.bib").read_text()
    paper = re.search(r"@misc\{paper,(.*?)\n\}", bib, re.DOTALL).group(1)
    assert PAPER_TITLE in paper
    assert re.search(r"doi = \{(.*?)\}", paper).group(1) == PAPER_DOI
    authors = re.search(r"author = \{(.*?)\},", paper).group(1).split(" and ")
    assert [a.split(",")[0] for a in authors] == PAPER_AUTHORS


def test_the_citation_file_references_the_paper():
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    (paper,) = [r for r in citation["references"] if r["title"] == PAPER_TITLE]
    assert paper["doi"] == PAPER_DOI and paper["year"] == 2024
    assert [a["family-names"] for a in paper["authors"]] == PAPER_AUTHORS


def test_the_repository_url_is_named_once_in_the_config_and_nowhere_else_differently():
    url, ref = install_cell.repository()
    raw = url.replace("https://github.com/", "https://raw.githubusercontent.com/", 1)
    readme = (ROOT / "README.md").read_text()
    named = re.findall(r"https://(?:raw\.githubusercontent|github)\.com/[\w.-]+/[\w.-]+", readme)
    assert named, "the README names no repository"
    assert set(named) == {url, raw}, f"the README names another repository: {set(named)}"
    assert f"git+{url}@{ref}" in readme and f"{raw}/{ref}/requirements.txt" in readme
    assert yaml.safe_load((ROOT / "CITATION.cff").read_text())["repository-code"] == url


def test_the_package_admits_colabs_preinstalled_versions_outside_the_stack():
    from packaging.requirements import Requirement

    seed = (ROOT / ".ci" / "colab-preinstalled.txt").read_text()
    source = r"googlecolab/backend-info.*\n# at commit [0-9a-f]{40} \(\d{4}-\d\d-\d\d"
    assert re.search(source, seed), "the seed file must name its source commit and date"
    colab = _pins(seed.splitlines())
    stack = {_normalise(name) for name in install_cell.STACK}
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    kept = []
    for line in project["dependencies"]:
        requirement = Requirement(line)
        name = _normalise(requirement.name)
        if name in colab and name not in stack:
            kept.append(name)
            assert colab[name] in requirement.specifier, (
                f"pyproject's {requirement} would move Colab's {name} {colab[name]}"
            )
    assert {"numpy", "pandas", "scipy", "matplotlib", "scikit-learn"} <= set(kept)


def test_the_readme_map_names_every_module_of_the_package():
    modules = {
        ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        for path in (ROOT / "sgb").rglob("*.py")
        if path.name != "__main__.py"
    }
    readme = (ROOT / "README.md").read_text()
    plots = re.search(r"`sgb\.plots` \| ([^\n]*)", readme).group(1)
    named = {m for m in modules if f"`{m}`" in readme}
    named |= {m for m in modules if m.startswith("sgb.plots.") and f"`{m[10:]}`" in plots}
    assert sorted(modules - named) == []


@pytest.mark.parametrize("notebook", NOTEBOOKS)
def test_no_line_of_inline_math_starts_where_markdown_would_read_a_list(notebook):
    """A formula wrapped so that a line starts with "- " or "+ " inside $...$ renders as a
    bullet and raw LaTeX: every such line is named."""
    cells = json.loads((ROOT / notebook).read_text())["cells"]
    broken = []
    for cell in cells:
        if cell["cell_type"] != "markdown":
            continue
        open_math = False
        for line in "".join(cell["source"]).splitlines():
            if not line.strip():
                open_math = False  # a blank line ends a paragraph, and any math in it
                continue
            if open_math and re.match(r"\s*([-+*]|\d+\.)\s", line):
                broken.append(line[:60])
            inline = line.replace("\\$", "").replace("$$", "")
            open_math ^= inline.count("$") % 2 == 1
    assert broken == []
