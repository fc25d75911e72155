"""``sgb.experiments.regime``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import numpy as np
import pytest
from committed import RECORDS, raw

from sgb import claims, genome
from sgb.experiments import regime as regime_runs
from sgb.provenance import read_results
from sgb.rl import checkpoints
from sgb.rl.regimes import authors_scale
from sgb.rl.runs import CHECKPOINT_DIR


def test_the_regime_table_is_the_runs_of_its_file():
    regime = raw("rl/regime_ant_cpu.json")
    table = regime_runs.regime_table(RECORDS("regime"))
    assert list(table.columns) == list(regime_runs.REGIME_COLUMNS.values())
    assert table["final return"].tolist() == [r["final_return"] for r in regime["results"]["runs"]]


def test_regime_names_its_arms_by_genome_then_more_types_first_and_none_without_them():
    regime = RECORDS("regime").model_dump(exclude_unset=True)
    summary = regime["results"]["summary"]
    sgb_arm = next(s for s in summary if s["cell_types"] is not None)
    landed = ((16, "authors_aliased"), (16, "authors"), (64, "authors"), (32, "authors"))
    regime["results"]["summary"] = [s for s in summary if s["cell_types"] is None] + [
        {**sgb_arm, "cell_types": k, "genome": genome} for k, genome in landed
    ]
    arms = regime_runs.regime(regime_runs.Regime.model_validate(regime))["regime_sgb"]
    assert [arm.split(":")[0] for arm in arms.split("; ")] == [
        "64 types",
        "32 types",
        "16 types",
        "16 types, pairs aliased",
    ]
    regime["results"]["summary"] = [s for s in summary if s["cell_types"] is None]
    assert regime_runs.regime(regime_runs.Regime.model_validate(regime))["regime_sgb"] == "none"


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


def test_a_runs_sigma_course_is_its_recorded_kernels_and_the_chapter_says_its_change():
    """Evaluations that recorded no spreads and the biases are left out; the committed
    64-type seed-0 run recorded all 11, from softplus(rho) near 0.0009 at step 0 down;
    each run is named by its arm, the aliased pairs apart from the per-pair 16 types."""
    regime = RECORDS("regime").model_dump(exclude_unset=True)
    run = next(r for r in regime["results"]["runs"] if r["cell_types"] is not None)
    sigmas = [
        None,
        {"h": 2e-3, "h/bias": 9.0, "out": 4e-3},
        {"h": 1e-3, "h/bias": 9.0, "out": 3e-3},
    ]
    made = {**run, "eval_steps": [0, 10, 20], "eval_sigmas": sigmas}
    steps, sigma, names = regime_runs.sigma_course(regime_runs.RegimeRun.model_validate(made))
    assert steps.tolist() == [10, 20] and names == ["h", "out"]
    assert sigma.tolist() == [[2e-3, 4e-3], [1e-3, 3e-3]]
    once = {**made, "eval_sigmas": [None, None, sigmas[2]]}
    assert regime_runs.sigma_course(regime_runs.RegimeRun.model_validate(once)) is None
    committed = RECORDS("regime")
    (k64,) = [r for r in committed.results.runs if (r.cell_types, r.seed) == (64, 0)]
    steps, sigma, names = regime_runs.sigma_course(k64)
    assert steps[0] == 0 and len(steps) == 11 and sigma.shape == (11, len(names))
    assert sigma[0].mean() == pytest.approx(float(genome.softplus(-7.0)), rel=0.05)
    change = f"({sigma[-1].mean() / sigma[0].mean() - 1:+.0%})"
    text = regime_runs.sigma_courses(committed)["regime_sigma_course"]
    assert f"64 types seed 0, {sigma[0].mean():.2g} at step 0 to " in text and change in text
    courses = regime_runs.sigma_courses_by_run(committed)
    aliased = [r for r in committed.results.runs if r.genome == "authors_aliased"]
    assert {f"16 types, pairs aliased seed {r.seed}" for r in aliased} <= set(courses)
    assert text.count("; ") + 1 == len(courses) and all(name in text for name in courses)


def test_a_smoke_regime_records_each_sgb_runs_spreads_against_its_means(tmp_path):
    """A smoke regime run writes, for its SGB run, each layer's mean sigma and mean |mu|
    as its checkpoint's actor holds them: at 320 steps sigma is still near its birth,
    softplus(-7), far below |mu|; the chapter's texts say both."""
    path = regime_runs.run("smoke", tmp_path)
    record = regime_runs.Regime.model_validate(read_results(path))
    (sgb,) = [r for r in record.results.runs if r.cell_types is not None]
    _, params, _, _ = checkpoints.load(tmp_path / CHECKPOINT_DIR / sgb.checkpoint)
    tables = genome.of_params(params.actor)
    assert [x.layer for x in sgb.layers] == list(tables)
    for layer in sgb.layers:
        g = tables[layer.layer]
        assert layer.mean_sigma == pytest.approx(float(np.mean(genome.sigma(g))))
        assert layer.mean_abs_mu == pytest.approx(float(np.mean(np.abs(g.mu))))
        assert 0.5 < layer.mean_sigma / float(genome.softplus(-7.0)) < 2
    texts = regime_runs.spreads(record)
    assert texts["regime_birth_sigma"].startswith(f"{float(genome.softplus(-7.0)):.2g} (rho -7")
    assert f"({1} runs, {len(sgb.layers)} layers)" in texts["regime_spreads"]


def test_the_regime_sweep_draws_each_arms_mean_and_sem_over_seeds_and_vanillas_band():
    """Figure 3C at the paper's budget on runs with known returns: vanilla's mean as a
    line inside its SEM band, each SGB arm's mean with its SEM bar (none for one seed),
    the aliased pairs hollow and beside their own count."""
    import matplotlib

    matplotlib.use("agg")
    from sgb.plots import rl as figures

    run = RECORDS("regime").results.runs[0]
    made = {
        (None, "authors"): [7000.0, 6900.0, 6800.0],
        (128, "authors"): [7600.0, 6500.0, 6800.0],
        (16, "authors"): [900.0, 500.0],
        (16, "authors_aliased"): [400.0],
    }
    runs = [
        run.model_copy(update={"cell_types": k, "genome": g, "seed": s, "final_return": r})
        for (k, g), returns in made.items()
        for s, r in enumerate(returns)
    ]
    ax = figures.plot_regime_sweep(runs)
    (vanilla,) = [line for line in ax.lines if line.get_linestyle() == "--"]
    assert vanilla.get_ydata()[0] == pytest.approx(6900.0)
    (band,) = ax.patches
    assert band.get_extents().height > 0
    drawn = {}
    for container in ax.containers:
        data, _, bars = container.lines
        (x,), (y,) = data.get_xdata(), data.get_ydata()
        sem = float(np.ptp(bars[0].get_segments()[0][:, 1])) / 2 if bars else None
        drawn[round(x, 2)] = (y, sem, data.get_markerfacecolor())
    assert sorted(drawn) == [16, 17.92, 128]
    assert drawn[128][:2] == pytest.approx(
        (20900 / 3, np.std(made[128, "authors"], ddof=1) / 3**0.5)
    )
    assert drawn[16][:2] == pytest.approx((700.0, 200.0))
    assert drawn[17.92][:2] == (400.0, None) and drawn[17.92][2] == "none"


def test_the_sweep_table_gives_each_arm_on_both_scales_paired_with_its_seeds_vanilla():
    """Runs with known returns: the fraction of vanilla pairs each run with the vanilla run
    of its seed (a seed without one is left out of it), the authors' scale is the runs'
    own, each mean ± SEM over seeds (the mean alone for one seed), arms in order."""
    regime = RECORDS("regime").model_dump(exclude_unset=True)
    run = regime["results"]["runs"][0]
    made = {
        (16, "authors_aliased"): {0: 500.0},
        (None, "authors"): {0: 8000.0, 1: 6000.0},
        (16, "authors"): {0: 800.0, 1: 1200.0, 2: 300.0},
    }
    regime["results"]["runs"] = [
        {**run, "cell_types": k, "genome": g, "seed": s, "final_return": r}
        | {"authors_scale": authors_scale("ant", r)}
        for (k, g), returns in made.items()
        for s, r in returns.items()
    ]
    table = regime_runs.sweep_table(regime_runs.Regime.model_validate(regime))
    assert table["arm"].tolist() == ["vanilla PPO", "16 types", "16 types, pairs aliased"]
    assert table["seeds"].tolist() == ["0, 1", "0, 1, 2", "0"]
    assert table["final return"].tolist() == ["7000 ± 1000", "767 ± 260", "500"]
    # seed 0 and 1 of 16 types against their own vanilla: 0.1 and 0.2
    assert table["fraction of vanilla"].tolist() == ["1.00 ± 0.00", "0.15 ± 0.05", "0.06"]
    scale = [authors_scale("ant", r) for r in made[None, "authors"].values()]
    sem = abs(scale[0] - scale[1]) / 2  # of two values
    assert table["authors' scale"][0] == f"{np.mean(scale):.2f} ± {sem:.2f}"


def test_their_aliased_pairs_fall_from_the_per_pair_128_types_and_are_set_against_its_16():
    """Two aliased 16-type runs 600 and 900 above the per-pair 16-type mean, in place of
    the committed aliased runs: the aliased fall leaves the per-pair 128-type arm (no
    level or shape row of its own), and the aliasing text is their difference at 16
    types, in fractions of vanilla."""
    regime = RECORDS("regime").model_dump(exclude_unset=True)
    runs = [r for r in regime["results"]["runs"] if r.get("genome") != "authors_aliased"]
    k16 = [r for r in runs if r["cell_types"] == 16 and r["genome"] == "authors"]
    base = np.mean([r["final_return"] for r in k16])
    aliased = [
        {**k16[seed], "genome": "authors_aliased", "final_return": base + extra}
        for seed, extra in ((0, 600.0), (1, 900.0))
    ]
    both = {**regime, "results": {**regime["results"], "runs": runs + aliased}}
    both = regime_runs.Regime.model_validate(both)
    steps = regime["provenance"]["config"]["ppo"]["total_steps"]
    setting = claims.figure3_setting(
        "ant", "authors_aliased", claims.REGIME_SETTINGS, regime_runs.ABLATIONS
    )
    mine = [r for r in regime_runs.regime_rows(both.results.runs, steps) if r.setting == setting]
    (fall,) = mine
    assert fall.key == "fig3.fall_16.regime.ant" and "128 types: the authors'" in setting
    vanilla = np.mean([r["final_return"] for r in runs if r["cell_types"] is None])
    top = np.mean([r["final_return"] for r in runs if r["cell_types"] == 128])
    assert fall.test.estimate == pytest.approx((top - base - 750.0) / vanilla)
    texts = regime_runs.regime(both)
    assert texts["regime_fall_aliased"] == f"{fall.ours}, **{fall.verdict}**"
    assert texts["regime_aliasing"].startswith(f"{750.0 / vanilla:+.2f} [")
    assert "seeds: aliased 2, per pair 3" in texts["regime_aliasing"]
