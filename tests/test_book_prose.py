"""The chapters' prose states no verdict by hand: every verdict word comes from a glued value."""

import re
from pathlib import Path

import nbformat

from sgb import validation

BOOK = Path(__file__).resolve().parent.parent / "book"
VERDICT_WORDS = re.compile(r"\b(not reproduced|reproduced|contradicted|inconclusive)\b", re.I)
GLUED = re.compile(r"\{glue(:\w+)?\}`[^`]*`")
# the scorecard defines the rule, so it names the verdicts
EXEMPT = ("scorecard", "claims")


def typed_verdicts(markdown: str) -> list[str]:
    """The verdict words of ``markdown`` outside glued values."""
    return VERDICT_WORDS.findall(GLUED.sub("", markdown))


def test_the_detector_sees_typed_words_and_not_glued_ones():
    assert typed_verdicts("The fall is *reproduced* here.") == ["reproduced"]
    assert typed_verdicts("It is {glue:md}`fall_verdict`; run `sgb reproduce fig3`.") == []


def test_no_chapter_types_a_verdict():
    found = {}
    for path in sorted(BOOK.glob("*.ipynb")) + sorted(BOOK.glob("*.md")):
        if any(word in path.stem for word in EXEMPT):
            continue
        if path.suffix == ".md":
            texts = [path.read_text()]
        else:
            notebook = nbformat.read(path, as_version=4)
            texts = [c.source for c in notebook.cells if c.cell_type == "markdown"]
        words = [w for text in texts for w in typed_verdicts(text)]
        if words:
            found[path.name] = words
    assert not found, f"verdicts typed in chapter prose (glue them from sgb.claims): {found}"


def test_the_book_shows_the_code_that_runs():
    """What a chapter shows is read from the package's files: a function verbatim, a
    method dedented out of its class."""
    import textwrap
    from pathlib import Path

    from sgb import book, genome
    from sgb.rl import agent

    shown = book.source(genome.draw_noise)
    assert shown.startswith("def draw_noise(") and shown in Path(genome.__file__).read_text()
    method = book.source(agent.Agent.birth)
    assert method.startswith("def birth(")
    assert textwrap.indent(method, "    ") in Path(agent.__file__).read_text()


def _checked_scale(x, factor: float):
    """A function with a docstring, argument checks and a comment, for the test below."""
    x = validation.array("x", x)
    if factor <= 0:
        raise ValueError("factor must be > 0")
    for name in ("x",):
        if name != "x":
            raise ValueError(name)
    # the method: one line
    return x * factor


def test_the_book_shows_the_lines_that_define_a_method_and_no_checks():
    """``show_source`` keeps the signature, the comments and the computation, and drops
    the docstring and every check; on the chapters' functions what it keeps is the file's
    own lines in order, valid Python, with no check left."""
    import ast

    from sgb import book, genome
    from sgb.rl.losses import ppo_loss

    assert book.defining_source(_checked_scale).splitlines() == [
        "def _checked_scale(x, factor: float):",
        "    # the method: one line",
        "    return x * factor",
    ]
    for obj in (genome.draw_noise, genome._individual_kernel, genome.layer_kl, ppo_loss):
        full, shown = book.source(obj).splitlines(), book.defining_source(obj).splitlines()
        ast.parse("\n".join(shown))
        assert not any("raise " in line or "validation." in line for line in shown)
        lines = iter(full)
        assert all(line in lines for line in shown)  # a subsequence of the file's lines
    assert len(book.defining_source(genome.layer_kl).splitlines()) < 0.5 * len(
        book.source(genome.layer_kl).splitlines()
    )


def test_a_table_shows_its_caption_and_readable_numbers_and_no_index():
    """Integers whole with thousands separated, other numbers to three figures, p below
    0.001 as "< 0.001" (escaped in HTML), text whole however long, no index column."""
    import pandas as pd

    from sgb import book

    setting = "64 types, rho from -5, a fresh draw per minibatch, " * 3
    frame = pd.DataFrame(
        {"setting": [setting, "b"], "return": [12345.0, 0.012345], "p": [2e-5, 0.0312]},
        index=[7, 8],
    )
    html = book.table(frame, "Returns per episode.", p_columns=["p"]).to_html()
    assert "<caption>Returns per episode.</caption>" in html
    assert setting.strip() in html and ">7<" not in html  # whole text, no index
    assert "12,345" in html and "0.0123" in html
    assert "&lt; 0.001" in html and "0.031" in html
    assert [book.number_text(x) for x in (3.0, 0.5, 250.4, float("nan"), "k16")] == [
        "3",
        "0.5",
        "250",
        "-",
        "k16",
    ]
