"""The package's import structure, read from its source with ``ast``.

Every ``import`` and ``from ... import`` of every module of ``sgb`` counts, at module
level and inside functions alike (a function-level import is still an edge of the
graph, only a later one). The graph holds the sgb-internal imports: ``from sgb.a import
b`` is an import of ``sgb.a.b`` where that is a module, else of ``sgb.a``.

The rules:

- no cycle among the modules;
- the top layer, ``TOP``, is the command line (``sgb.__main__``), the background queue
  that runs it (``sgb.grid``) and the gatherers of the experiments' scorecard rows and
  texts (``sgb.gather``, ``sgb.chapters``): no other module outside ``sgb.experiments`` imports
  ``sgb.experiments`` or a module under it;
- no experiment (``sgb.experiments.X``) imports another (``sgb.experiments.Y``) or the
  registry (the package ``sgb.experiments``): what experiments share lies below them;
- the README's map of the layers is true: every module has its place there (its own row,
  or the row of a package above it; a package ``__init__`` the layer its heading names),
  and none imports from a layer after its own.
"""

import ast
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "sgb"
README = PACKAGE.parent / "README.md"
EXPERIMENTS = "sgb.experiments"
# the modules that gather the experiments: the command line, the queue, the scorecard's
# rows and the chapters' texts
TOP = frozenset({"sgb.__main__", "sgb.grid", "sgb.gather", "sgb.chapters"})


def module_name(path: Path) -> str:
    """The dotted name of the module at ``path`` under the package."""
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules() -> dict[str, Path]:
    """Every module of the package: dotted name -> its file."""
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def imports_of(name: str, path: Path, known: set[str]) -> set[str]:
    """The sgb modules that the module ``name`` (at ``path``) imports, anywhere in it."""
    found = set()
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: resolved against this module's package
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                found.add(sub if sub in known else base)
    return {m for m in found if m in known and m != name}


def graph() -> dict[str, set[str]]:
    """The package's import graph: module -> the sgb modules it imports."""
    files = modules()
    known = set(files)
    return {name: imports_of(name, path, known) for name, path in files.items()}


def cycle(edges: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``edges`` (its modules, the first repeated at the end), or None."""
    state: dict[str, int] = {}  # 1 on the path, 2 done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(edges[node]):
            if state.get(nxt) == 1:
                return [*path[path.index(nxt) :], nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        path.pop()
        state[node] = 2
        return None

    for node in sorted(edges):
        if node not in state and (found := visit(node)):
            return found
    return None


def is_experiment(name: str) -> bool:
    return name == EXPERIMENTS or name.startswith(EXPERIMENTS + ".")


def upward(edges: dict[str, set[str]]) -> list[str]:
    """Imports of the experiments from below them: ``importer -> imported``."""
    return [
        f"{a} -> {b}"
        for a, targets in sorted(edges.items())
        if not is_experiment(a) and a not in TOP
        for b in sorted(targets)
        if is_experiment(b)
    ]


def sideways(edges: dict[str, set[str]]) -> list[str]:
    """Imports among the experiments, or of their registry by one of them."""
    return [
        f"{a} -> {b}"
        for a, targets in sorted(edges.items())
        if a.startswith(EXPERIMENTS + ".")
        for b in sorted(targets)
        if is_experiment(b)
    ]


def readme_layers(text: str) -> tuple[list[str], dict[str, str], dict[str, str]]:
    """The README's map of the layers: the layers in order (each a bold heading), each row's
    module -> its layer, and each module a heading names -> its layer."""
    section = text.split("## Map of the layers", 1)[1].split("\n## ", 1)[0]
    order: list[str] = []
    rows: dict[str, str] = {}
    named: dict[str, str] = {}
    prose = ""  # a heading and the lines of its paragraph
    for line in section.splitlines():
        if heading := re.match(r"\*\*(.+?)\*\*(.*)", line):
            order.append(heading.group(1))
            prose = heading.group(2)
        elif row := re.match(r"\| `(sgb[\w.]*)` \|", line):
            rows[row.group(1)] = order[-1]
        elif line.strip() and not line.startswith("|") and prose:
            prose += " " + line
        else:
            prose = ""
        if order and prose:
            named |= dict.fromkeys(re.findall(r"`(sgb[\w.]*)`", prose), order[-1])
    return order, rows, named


def layer_of(name: str, rows: dict[str, str], named: dict[str, str]) -> str | None:
    """The layer of module ``name``: its row's, else the row's of the nearest package above
    it, else the layer whose heading names it; None where the map has no place for it."""
    parts = name.split(".")
    for n in range(len(parts), 1, -1):
        if ".".join(parts[:n]) in rows:
            return rows[".".join(parts[:n])]
    return named.get(name)


def against_the_map(edges: dict[str, set[str]], text: str) -> tuple[list[str], list[str]]:
    """The modules the map has no place for, and the imports from a later layer."""
    order, rows, named = readme_layers(text)
    place = {name: layer_of(name, rows, named) for name in edges}
    missing = sorted(name for name, layer in place.items() if layer is None)
    later = [
        f"{a} ({place[a]}) -> {b} ({place[b]})"
        for a, targets in sorted(edges.items())
        for b in sorted(targets)
        if place[a] and place[b] and order.index(place[b]) > order.index(place[a])
    ]
    return missing, later


def test_the_graph_is_read():
    edges = graph()
    assert "sgb.experiments.fig2" in edges and "sgb.rl.ppo" in edges
    assert "sgb.rl.ppo" in edges["sgb.rl.trainer"] or "sgb.rl.trainer" in edges["sgb.rl.ppo"]


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("from sgb.rl import ppo", {"sgb.rl.ppo"}),
        ("from sgb.rl.ppo import train", {"sgb.rl.ppo"}),
        ("def f():\n    import sgb.rl.ppo", {"sgb.rl.ppo"}),
        ("from . import ppo", {"sgb.rl.ppo"}),
        ("import numpy", set()),
    ],
)
def test_imports_are_read_at_every_level(tmp_path, source, expected):
    path = tmp_path / "x.py"
    path.write_text(source)
    assert imports_of("sgb.rl.x", path, {"sgb.rl", "sgb.rl.ppo", "sgb.rl.x"}) == expected


def test_the_rules_catch_what_they_forbid():
    edges = {
        "sgb.a": {"sgb.b"},
        "sgb.b": {"sgb.a", "sgb.experiments.x"},
        "sgb.experiments.x": {"sgb.experiments.y", "sgb.experiments"},
        "sgb.experiments.y": set(),
        "sgb.experiments": set(),
    }
    assert cycle(edges) == ["sgb.a", "sgb.b", "sgb.a"]
    assert upward(edges) == ["sgb.b -> sgb.experiments.x"]
    assert sideways(edges) == [
        "sgb.experiments.x -> sgb.experiments",
        "sgb.experiments.x -> sgb.experiments.y",
    ]


def test_the_map_catches_a_module_out_of_place():
    text = """## Map of the layers

**Low** (`sgb`)

| `sgb.a` | a |
| `sgb.plots` | figures |

**High**: the command line
(`sgb.__main__`) runs it

## Next
"""
    edges = {"sgb": set(), "sgb.a": {"sgb.__main__"}, "sgb.plots.x": {"sgb.a"}}
    edges |= {"sgb.__main__": {"sgb.plots.x"}, "sgb.b": set()}
    assert against_the_map(edges, text) == (["sgb.b"], ["sgb.a (Low) -> sgb.__main__ (High)"])


def test_no_cycle():
    assert cycle(graph()) is None


def test_no_upward_import_of_the_experiments():
    assert upward(graph()) == []


def test_no_experiment_imports_another():
    assert sideways(graph()) == []


def test_the_readme_map_is_true_to_the_imports():
    missing, later = against_the_map(graph(), README.read_text())
    assert missing == [], "modules the README's map of the layers leaves out"
    assert later == [], "imports from a layer the README's map puts after the importer's"
