"""``sgb.prose``: every name a chapter's prose glues has its text, from the committed files,
and missing results give the documented fallbacks."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from sgb import book, chapters, claims, gather, prose
from sgb.experiments import fig2, fig3, fig4_5, regime_gait, regime_peer, sgb_full
from sgb.experiments import populations as population_runs
from sgb.experiments import regime as regime_runs
from sgb.paths import committed_results

BOOK = Path(__file__).resolve().parent.parent / "book"
RECORDS = gather.records()  # the committed results, read by experiment


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
    assert texts["regime_steps"] == f"{int(vanilla[0].eval_steps[-1]):,}"  # all digits
    bench = RECORDS("bench_backends").results.throughput
    ratio = bench["mjx"].train_steps_per_s / bench["spring"].train_steps_per_s
    assert prose.backends(RECORDS("bench_backends"))["mjx_vs_spring"] == (f"{ratio:.2f}x")
    fashion = RECORDS("fig2").results
    dense = fashion.ours.summary.dense.mean[0]
    assert fig2.figure2(fashion, {})["f2_dense"] == f"{100 * dense:.1f} %"


def test_regime_without_sgb_arms_says_none():
    regime = RECORDS("regime").model_dump(exclude_unset=True)
    summary = regime["results"]["summary"]
    regime["results"]["summary"] = [s for s in summary if s["cell_types"] is None]
    assert regime_runs.regime(regime_runs.Regime.model_validate(regime))["regime_sgb"] == "none"


def test_glue_all_glues_every_text(monkeypatch):
    glued = {}
    monkeypatch.setattr(book, "glue", lambda name, text: glued.__setitem__(name, text))
    book.glue_all({"a": "1 %", "b": "**reproduced**"})
    assert glued == {"a": "1 %", "b": "**reproduced**"}


def test_the_variants_texts_say_a_known_shift_and_a_null_one():
    """Rewritten to known accuracies: the KL per type pair 5 points above the authors' at
    every ratio, our rho start level with them (the same values, the seeds' order turned)."""
    full = RECORDS("sgb_full").model_dump(exclude_unset=True)
    cells = [c for c in full["results"]["cells"].values() if c["variant"] == "authors"]
    rewritten = {}
    for i, cell in enumerate(cells):
        rewritten[f"authors{i}"] = cell
        rewritten[f"per_pair{i}"] = {
            **cell,
            "variant": "per_pair",
            "accuracy": cell["accuracy"] + 0.05,
        }
        twin = next(
            c
            for c in cells
            if c["setting"] == cell["setting"] and c["seed"] == (cell["seed"] + 1) % 3
        )
        rewritten[f"rho_ours{i}"] = {**twin, "variant": "rho_ours"}
    full["results"]["cells"] = rewritten
    texts = sgb_full.sgb_full(sgb_full.SgbFull.model_validate(full))
    assert texts["full_pair_shift"].startswith("+5.0 to +5.0 points over 7 ratios (7 of whose")
    assert texts["full_rho_shift"].startswith("+0.0 to +0.0 points over 7 ratios (0 of whose")
    assert texts["full_rho_mean_shift"].startswith("+0.0 to +0.0 points over 7 ratios")
    assert texts["full_rho_conclusion"].endswith("at none of the 7 ratios")


def test_the_regime_texts_carry_its_rows_once_two_seeds_per_arm_land():
    """With seed 0 alone no row; with two seeds of vanilla and 128 types the level's text
    is its row's estimate and verdict, and the fall still has none."""
    regime = RECORDS("regime").model_dump(exclude_unset=True)
    runs = regime["results"]["runs"]
    seed0 = {
        **regime,
        "results": {**regime["results"], "runs": [r for r in runs if r["seed"] == 0]},
    }
    runs_of_seed0 = seed0["results"]["runs"]
    seed0 = regime_runs.Regime.model_validate(seed0)
    assert regime_runs.regime(seed0)["regime_level"].startswith("no row yet")
    second = [
        {**r, "seed": 1, "final_return": r["final_return"] + 150.0}
        for r in runs
        if r["seed"] == 0 and r["cell_types"] in (None, 128)
    ]
    both = {**regime, "results": {**regime["results"], "runs": runs_of_seed0 + second}}
    both = regime_runs.Regime.model_validate(both)
    steps = regime["provenance"]["config"]["ppo"]["total_steps"]
    (level,) = regime_runs.regime_rows(both.results.runs, steps)
    texts = regime_runs.regime(both)
    assert texts["regime_level"] == f"{level.ours}, **{level.verdict}**"
    assert texts["regime_fall"].startswith("no row yet")


def test_the_variability_texts_are_the_rows_of_each_setting():
    """The regime's genome, then each setting's genomes, as the scorecard's rows say."""
    card = claims.by_key(gather.scorecard(committed_results()))
    texts = fig4_5.variability(card)
    (regime,) = card["title.variability.regime"]
    assert texts["variability_regime"] == f"{regime.ours} % of the return, **{regime.verdict}**"
    ours = [r for r in card["title.variability"] if ", our genome, " in r.setting]
    assert texts["variability_ours"].count("**") == 2 * len(ours) > 0
    assert set(fig4_5.variability({}).values()) == {prose.NOT_RUN}


def test_the_peer_texts_set_the_authors_run_against_the_interval_of_ours():
    """Three seeds of ours, the authors' one run inside their interval for vanilla and
    outside it for the aliased layer; nothing from a point they did not evaluate."""

    def run(label: str, last: list[float]) -> list[dict]:
        steps = list(regime_peer.THEIR_STEPS)
        return [{"label": label, "eval_steps": steps, "eval_returns": [0.0, 0.0, x]} for x in last]

    runs = run("vanilla", [250.0, 300.0, 350.0]) + run("k64_aliased", [-100.0, -90.0, -110.0])
    results = {"env": "ant", "runs": [], "comparison": regime_peer.compare(runs)}
    stored = json.loads(json.dumps(results))  # as the file holds it: the interval a list
    texts = regime_peer.regime_peer(regime_peer.RegimePeerResults.model_validate(stored))
    assert texts["peer_vanilla_ours"].startswith("250, 300, 350 at 1,638,400 steps (mean 300")
    assert (texts["peer_vanilla_theirs"], texts["peer_vanilla_inside"]) == ("279.8", "inside")
    assert (texts["peer_aliased_theirs"], texts["peer_aliased_inside"]) == ("-351.2", "outside")
    assert set(regime_peer.regime_peer(None).values()) == {prose.NOT_RUN}


def test_the_gait_texts_list_each_arms_speeds_and_count_the_walkers():
    """Vanilla first, then the most cell types to the fewest; a run below the walking
    speed is not counted as walking."""

    def run(k, seed, speed):
        walked = {"cell_types": k, "seed": seed, "forward_velocity": speed, "walks": speed >= 1}
        return walked | {"genome": "authors", "window_return": 1000.0, "forward_velocity_sem": 0.1}

    runs = [run(16, 0, 0.4), run(None, 1, 7.0), run(128, 0, 8.0), run(None, 0, 7.5)]
    results = regime_gait.RegimeGaitResults.model_validate({"walking_speed": 1.0, "runs": runs})
    texts = regime_gait.regime_gait(results)
    assert texts["gait_runs"] == (
        "vanilla 7.50, 7.00 m/s (seeds 0, 1); 128 types 8.00 m/s (seed 0); "
        "16 types 0.40 m/s (seed 0)"
    )
    assert texts["gait_walks"] == "3 of the 4 runs walk (at least 1 m/s)"
    assert set(regime_gait.regime_gait(None).values()) == {prose.NOT_RUN}
