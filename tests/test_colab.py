"""The chapters as read outside the built book (``sgb.colab``): a value glued as myst-nb
stores it comes back in the prose, figures are numbered as the book numbers them, the
book's citations resolve, a caption follows its figure, and a role left over is caught."""

import json
from pathlib import Path

import pytest

from sgb import colab

ROOT = Path(__file__).resolve().parent.parent


def _glue_output(name: str, text: str) -> dict:
    """A value glued with ``display=False`` as myst-nb's ``glue`` writes it."""
    prefix = "application/papermill.record/"
    return {
        "output_type": "display_data",
        "metadata": {"scrapbook": {"name": name, "mime_prefix": prefix}},
        "data": {prefix + "text/markdown": text, prefix + "text/plain": "<Markdown>"},
    }


def _chapter(caption: str = "Accuracy at {glue:md}`acc`.") -> dict:
    figure = {"mystnb": {"figure": {"caption": caption, "name": "fig-acc"}}}
    return {
        "cells": [
            {"cell_type": "markdown", "id": "a", "metadata": {}, "source": "Intro."},
            {"cell_type": "code", "id": "b", "metadata": figure, "outputs": [], "source": "x"},
            {
                "cell_type": "markdown",
                "id": "c",
                "metadata": {},
                "source": "It reaches {glue:md}`acc` ({numref}`fig-acc`), as "
                "{cite:t}`paper` say and others agree {cite:p}`zador2019`.",
            },
        ],
        "metadata": {},
        "nbformat": 4,
        "nbformat_minor": 5,
    }


def test_an_edition_writes_in_what_the_book_shows():
    source = _chapter()
    values = colab.glued([_glue_output("acc", "**83.1 %**")])
    assert values == {"acc": "**83.1 %**"}
    cites = colab.citations((ROOT / "references.bib").read_text())
    figures = colab.figure_numbers({4: source})
    assert figures == {"fig-acc": "4.1"}
    made = colab.edition(source, values, figures, cites)
    texts = [c["source"] for c in made["cells"]]
    assert texts[2] == "**Fig. 4.1.** Accuracy at **83.1 %**."
    assert texts[3] == (
        "It reaches **83.1 %** (Fig. 4.1), as Lachi et al. (2024) say and others agree "
        "(Zador, 2019)."
    )
    assert colab.leftover_roles(made) == []
    assert all(c["outputs"] == [] for c in made["cells"] if c["cell_type"] == "code")


def test_an_unknown_value_or_a_leftover_role_is_named():
    source = _chapter()
    with pytest.raises(KeyError, match="no glued value named 'acc'"):
        colab.edition(source, {}, {"fig-acc": "4.1"}, {"paper": ("A", "2024")})
    left = colab.leftover_roles(source)
    assert [text.split("`")[0] for text in left] == [
        "{glue:md}",
        "{numref}",
        "{cite:t}",
        "{cite:p}",
    ]


def test_every_chapter_role_resolves_against_the_books_figures_and_bibliography():
    """Every {numref} and {cite} of the chapters names a figure or an entry that exists."""
    books = {p: json.loads(p.read_text()) for p in sorted((ROOT / "book").glob("*.ipynb"))}
    figures = colab.figure_numbers(
        {colab.chapter_number(p): nb for p, nb in books.items() if colab.chapter_number(p)}
    )
    cites = colab.citations((ROOT / "references.bib").read_text())
    for notebook in books.values():
        for cell in notebook["cells"]:
            if cell["cell_type"] == "markdown":
                text = "".join(cell["source"])
                # glued values come from a run: stand in a placeholder for each
                values = {m[1]: "v" for m in colab.ROLE.findall(text) if m[0].startswith("glue")}
                assert "{numref}" not in colab.fill(text, values, figures, cites)
