"""``sgb.prose``: every name a chapter's prose glues has its text, from the committed files,
and missing results give the documented fallbacks."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from committed import RECORDS

from sgb import book, chapters, claims, gather, prose
from sgb.experiments import fig2, fig3, fig4_5
from sgb.experiments import populations as population_runs
from sgb.experiments import regime as regime_runs
from sgb.paths import committed_results

BOOK = Path(__file__).resolve().parent.parent / "book"


def prose_names(chapter: str) -> set[str]:
    """The glue names of the ``{glue}`` roles in a chapter's markdown cells."""
    notebook = json.loads((BOOK / f"{chapter}.ipynb").read_text())
    text = "".join("".join(c["source"]) for c in notebook["cells"] if c["cell_type"] == "markdown")
    return set(re.findall(r"\{glue(?::\w+)?\}`([^`]+)`", text))


@pytest.fixture(scope="module")
def card() -> prose.Card:
    return claims.by_key(gather.scorecard(committed_results()))


@pytest.mark.parametrize("chapter", sorted(chapters.CHAPTERS))
def test_each_name_of_the_prose_is_glued_from_results_or_computed(chapter, card):
    texts = chapters.texts(chapter, card=card)
    computed = chapters.COMPUTED[chapter]
    assert sorted(prose_names(chapter) - computed - set(texts)) == []
    assert not computed & set(texts)
    assert all(isinstance(t, str) and t for t in texts.values())


def test_each_chapter_glues_its_texts_in_one_call():
    """The chapters of ``chapters.CHAPTERS`` glue their texts from it, and no other
    chapter glues a text of ``sgb.prose``."""
    for path in sorted(BOOK.glob("*.ipynb")):
        notebook = json.loads(path.read_text())
        code = "".join("".join(c["source"]) for c in notebook["cells"] if c["cell_type"] == "code")
        call = f'book.glue_all(chapters.texts("{path.stem}", RESULTS))'
        assert code.count(call) == (path.stem in chapters.CHAPTERS), path.name
        assert "glue_all(prose." not in code, path.name


def test_row_texts_read_the_scorecard_row(card):
    row = card["fig3.fall_16.ant"][0]
    texts = prose.row_texts("fall", row)
    assert texts["fall_verdict"] == f"**{row.verdict}**"
    assert texts["fall_ours"] == row.ours
    assert texts["fall_detectable"] == f"{row.test.detectable:.3g}"
    assert texts["fall_decide"] == (row.decide or "nothing more")
    untested = prose.row_texts("cifar", card["fig2.cifar"][0])
    assert untested["cifar_detectable"] == "none"


def test_missing_rows_and_files_give_the_fallback_texts():
    sweeps = [RECORDS("fig3", env) for env in ("ant", "halfcheetah")]
    texts = fig3.figure3(*sweeps, card={})
    for name in ("level_ours", "fall_authors", "cheetah_fall_ours"):
        assert {texts[f"{name}_{part}"] for part in (*prose.ROW_PARTS, "power")} == {"not yet run"}
    assert texts["typing_ours_verdict"] == "not yet run (fewer than 2 seeds)"
    assert texts["ant_vanilla_n"] == "10"  # the sweep's own numbers do not need the card
    missing = population_runs.populations(None)
    assert missing.pop("pop_complete") == "none of the genomes"
    assert set(missing.values()) == {prose.NOT_RUN}
    assert len(missing) == 2 * 2 * len(prose.ROW_PARTS)  # 2 settings x 2 figures
    assert set(fig4_5.figures4_5({}).values()) == {prose.NOT_RUN}
    assert set(population_runs.regime_populations(None).values()) == {prose.NOT_RUN}


def test_the_texts_are_the_files_values():
    regime = RECORDS("regime")
    vanilla = [r for r in regime.results.runs if r.cell_types is None]
    texts = regime_runs.regime(regime)
    mean = np.mean([r.final_return for r in vanilla])
    assert texts["regime_vanilla"].startswith(f"{mean:.0f}")
    assert texts["regime_vanilla"].endswith(f"over {len(vanilla)} seed" + "s" * (len(vanilla) > 1))
    wall = np.mean([r.wall_time_s for r in vanilla])
    assert texts["regime_wall"] == f"{wall / 3600:.1f} h"
    timed = [r.cpu_time_s for r in regime.results.runs if r.cpu_time_s is not None]
    if timed:
        assert texts["regime_cpu"].startswith(f"{np.mean(timed) / 3600:.1f} h ({len(timed)} of ")
    else:
        assert texts["regime_cpu"] == "not recorded by the runs finished so far"
    assert texts["regime_steps"] == f"{int(vanilla[0].eval_steps[-1]):,}"  # all digits
    bench = RECORDS("bench_backends").results.throughput
    ratio = bench["mjx"].train_steps_per_s / bench["spring"].train_steps_per_s
    assert prose.backends(RECORDS("bench_backends"))["mjx_vs_spring"] == (f"{ratio:.2f}x")
    fashion = RECORDS("fig2").results
    dense = fashion.ours.summary.dense.mean[0]
    assert fig2.figure2(fashion, {})["f2_dense"] == f"{100 * dense:.1f} %"


def test_glue_all_glues_every_text(monkeypatch):
    glued = {}
    monkeypatch.setattr(book, "glue", lambda name, text: glued.__setitem__(name, text))
    book.glue_all({"a": "1 %", "b": "**reproduced**"})
    assert glued == {"a": "1 %", "b": "**reproduced**"}
