"""The chapters' prose states no verdict by hand: every verdict word comes from a glued value."""

import re
from pathlib import Path

import nbformat

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
