"""The book's chapters as a reader meets them outside the built book (Colab, Jupyter): each
notebook with its glued values, figure numbers, citations and figure captions written in.

The web book fills ``{glue:md}`name``` roles from the values a chapter glues as it runs,
numbers figures for ``{numref}`label```, turns ``{cite:p}`key``` into a reference and
shows each figure's caption from its cell's metadata (``mystnb.figure``). A notebook
opened elsewhere shows none of that: only the role text. ``edition`` makes the version
that does: from the chapter's source and the same chapter as the book's build executed
it (the values myst-nb keeps in ``NAME.glue.json`` beside it), every role replaced by the
text the book shows for it, and a caption cell after every captioned figure.
``python -m sgb.colab BUILD OUT`` writes the editions of every chapter of a finished
build (``BUILD/jupyter_execute/book``) to ``OUT`` and fails, naming the notebook and the
text, if any role is left (``leftover_roles``).
"""

import json
import re
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

ROLE = re.compile(r"\{(glue:md|glue:text|glue|numref|cite:p|cite:t)\}`([^`]*)`")
LEFTOVER = re.compile(r"\{(?:glue(?::\w+)?|numref|cite(?::\w+)?)\}`")
Notebook = dict[str, Any]  # a notebook as nbformat's JSON
BUILD_ONLY = ("status.ipynb",)  # the build's own record: no edition


def glued(outputs: Iterable[dict]) -> dict[str, str]:
    """The values glued in ``outputs`` (notebook outputs, as myst-nb's ``glue`` writes
    them): name -> its markdown (or plain) text."""
    values = {}
    for output in outputs:
        scrapbook = output.get("metadata", {}).get("scrapbook", {})
        name = scrapbook.get("name")
        if name is None:
            continue
        prefix = scrapbook.get("mime_prefix", "")  # myst-nb's, for a value not displayed
        data = {k.removeprefix(prefix): v for k, v in output.get("data", {}).items()}
        text = data.get("text/markdown", data.get("text/plain"))
        values[name] = "".join(text) if isinstance(text, list) else str(text)
    return values


def executed_values(executed: Path) -> dict[str, str]:
    """The values a chapter glued when the build ran it: from its executed notebook and
    the ``.glue.json`` beside it, where myst-nb keeps them."""
    notebook = json.loads(executed.read_text())
    outputs = [o for cell in notebook["cells"] for o in cell.get("outputs", [])]
    store = executed.with_suffix(".glue.json")
    if store.exists():
        outputs += list(json.loads(store.read_text()).values())
    return glued(outputs)


def figure(cell: dict) -> dict | None:
    """A code cell's figure metadata (``name``, ``caption``), or ``None``."""
    return cell.get("metadata", {}).get("mystnb", {}).get("figure")


def figure_numbers(chapters: dict[int, Notebook]) -> dict[str, str]:
    """Every figure label of the chapters (chapter number -> source notebook) -> its number
    as the book prints it: ``"5.3"`` for the third captioned figure of chapter 5."""
    numbers = {}
    for chapter, notebook in sorted(chapters.items()):
        captioned = [figure(c) for c in notebook["cells"] if figure(c) and "caption" in figure(c)]
        for i, meta in enumerate(captioned, start=1):
            if "name" in meta:
                numbers[meta["name"]] = f"{chapter}.{i}"
    return numbers


def citations(bib: str) -> dict[str, tuple[str, str]]:
    """Each entry of a BibTeX text: key -> (authors as the book cites them, year)."""
    out = {}
    for key, body in re.findall(r"@\w+\{([^,\s]+),(.*?)\n\}", bib, flags=re.S):
        author = re.search(r"author\s*=\s*\{(.*?)\},?\n", body, flags=re.S)
        year = re.search(r"year\s*=\s*\{?(\d{4})", body)
        if author is None or year is None:
            raise ValueError(f"bibliography entry {key!r} has no author or year")
        names = [n.strip() for n in author.group(1).split(" and ")]
        surnames = [n.split(",")[0].strip("{} ") for n in names if n != "others"]
        if len(surnames) == 1 and "others" not in names:
            who = surnames[0]
        elif len(surnames) == 2 and "others" not in names:
            who = f"{surnames[0]} and {surnames[1]}"
        else:
            who = f"{surnames[0]} et al."
        out[key] = (who, year.group(1))
    return out


def fill(
    text: str,
    values: dict[str, str],
    figures: dict[str, str],
    cites: dict[str, tuple[str, str]],
) -> str:
    """``text`` (markdown) with every role replaced by what the book shows for it; a
    ``KeyError`` naming a glue name, figure label or citation key that is not known."""

    def one(match: re.Match) -> str:
        role, target = match.groups()
        if role.startswith("glue"):
            if target not in values:
                raise KeyError(f"no glued value named {target!r}")
            return values[target].strip()
        if role == "numref":
            if target not in figures:
                raise KeyError(f"no figure labelled {target!r}")
            return f"Fig. {figures[target]}"
        entries = []
        for key in (k.strip() for k in target.split(",")):
            if key not in cites:
                raise KeyError(f"no bibliography entry {key!r}")
            entries.append(cites[key])
        if role == "cite:t":
            return "; ".join(f"{who} ({year})" for who, year in entries)
        return "(" + "; ".join(f"{who}, {year}" for who, year in entries) + ")"

    return ROLE.sub(one, text)


def _source(cell: dict) -> str:
    source = cell["source"]
    return "".join(source) if isinstance(source, list) else source


def edition(
    source: Notebook,
    values: dict[str, str],
    figures: dict[str, str],
    cites: dict[str, tuple[str, str]],
) -> Notebook:
    """The chapter ``source`` as read outside the book: its markdown with the ``values``
    the build glued written in (``executed_values``), and a caption cell
    (``**Fig. N.k.** caption``) after each captioned figure; outputs stay stripped."""
    cells = []
    for cell in source["cells"]:
        cell = json.loads(json.dumps(cell))
        if cell["cell_type"] == "markdown":
            cell["source"] = fill(_source(cell), values, figures, cites)
        cells.append(cell)
        meta = figure(cell) if cell["cell_type"] == "code" else None
        if meta and "caption" in meta:
            number = figures.get(meta.get("name", ""), "")
            caption = fill(meta["caption"], values, figures, cites)
            label = f"**Fig. {number}.** " if number else ""
            cells.append(
                {
                    "cell_type": "markdown",
                    "id": f"{cell.get('id', 'figure')}-caption"[:64],
                    "metadata": {},
                    "source": f"{label}{caption}",
                }
            )
    return {**source, "cells": cells}


def leftover_roles(notebook: Notebook) -> list[str]:
    """Every piece of role text left in ``notebook``'s markdown cells."""
    found = []
    for cell in notebook["cells"]:
        if cell["cell_type"] == "markdown":
            text = _source(cell)
            found += [text[m.start() : m.start() + 60] for m in LEFTOVER.finditer(text)]
    return found


def chapter_number(path: Path) -> int | None:
    """The chapter number of a notebook named ``NN_*.ipynb``; ``None`` for other pages."""
    head = path.name.split("_", 1)[0]
    return int(head) if head.isdigit() else None


def write_editions(book: Path, executed_dir: Path, bib: Path, out: Path) -> list[Path]:
    """The edition of every notebook of ``book`` (the source folder), from its run in
    ``executed_dir``, written to ``out``; a ``ValueError`` naming any role left."""
    sources = {
        p: json.loads(p.read_text())
        for p in sorted(book.glob("*.ipynb"))
        if p.name not in BUILD_ONLY
    }
    numbered = {chapter_number(p): nb for p, nb in sources.items() if chapter_number(p)}
    figures = figure_numbers(numbered)
    cites = citations(bib.read_text())
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for path, notebook in sources.items():
        run = executed_dir / path.name
        if not run.exists():
            raise ValueError(f"{path.name} has no executed copy in {executed_dir}")
        made = edition(notebook, executed_values(run), figures, cites)
        left = leftover_roles(made)
        if left:
            raise ValueError(f"{path.name}'s edition still holds role text: {left[:3]}")
        target = out / path.name
        target.write_text(json.dumps(made, indent=1, ensure_ascii=False) + "\n")
        written.append(target)
    return written


def main(argv: list[str]) -> int:
    """``python -m sgb.colab BUILD OUT``: the editions of a finished ``make book``."""
    if len(argv) != 2:
        print("usage: python -m sgb.colab BUILD_DIR OUT_DIR", file=sys.stderr)
        return 2
    build, out = Path(argv[0]), Path(argv[1])
    root = Path(__file__).resolve().parent.parent
    try:
        written = write_editions(
            root / "book", build / "jupyter_execute" / "book", root / "references.bib", out
        )
    except (ValueError, KeyError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    print(f"wrote {len(written)} notebooks with their numbers and captions to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
