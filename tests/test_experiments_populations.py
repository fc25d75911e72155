"""The populations experiment: its summaries on returns of known between and within
variance, its pooling, and a smoke run end to end that resumes without evaluating again."""

import json
import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats as scipy_stats

from sgb import (
    stats,
    verdicts,
)
from sgb.experiments import (
    populations,
)
from sgb.experiments import populations as population_runs
from sgb.paths import committed_results
from sgb.provenance import jsonable, read_results
from sgb.rl import checkpoints
from sgb.rl.ppo import TrainResult


def _population(rng, n: int, episodes: int, sd_between: float, sd_within: float, mean=10.0):
    """Returns (n, episodes): individual i's level mean + b_i, b_i ~ N(0, sd_between^2),
    plus episode noise N(0, sd_within^2)."""
    levels = mean + rng.normal(0, sd_between, (n, 1))
    return levels + rng.normal(0, sd_within, (n, episodes))


def test_the_split_recovers_a_known_icc_and_reliability():
    rng = np.random.default_rng(0)
    # ICC 1 / (1 + 4) = 0.2; a 32-episode mean: 32 x 0.2 / (1 + 31 x 0.2) = 0.89
    summary = populations.body_summary(_population(rng, 400, 32, 1.0, 2.0))
    split = summary["variance_split"]
    assert split["icc_ci"][0] < 0.2 < split["icc_ci"][1]
    assert split["reliability"] == pytest.approx(32 * 0.2 / 7.2, abs=0.03)
    assert split["between_var"] == pytest.approx(1.0, rel=0.25)
    assert split["within_var"] == pytest.approx(4.0, rel=0.05)
    # measured directly, the two halves' means agree as the ANOVA predicts
    assert summary["split_half"]["episodes"] == 32
    assert summary["split_half"]["reliability"] == pytest.approx(split["reliability"], abs=0.05)
    assert "between_sd_bound" not in summary  # reliable enough: no bound is needed
    assert summary["episodes_for_target"] == pytest.approx(16, rel=0.3)


def test_an_unreliable_measurement_bounds_the_sd_between_individuals():
    rng = np.random.default_rng(1)
    held = 0
    for _ in range(100):
        x = _population(rng, 100, 4, 1.0, 2.0, mean=50.0)  # reliability of 4 episodes: 0.5
        summary = populations.body_summary(x)
        held += summary["between_sd_bound"] >= 1.0  # the true SD between individuals
    assert held >= 93  # an upper 97.5 % bound
    assert summary["variance_split"]["reliability"] < 0.8
    assert summary["between_sd_bound_percent"] == pytest.approx(
        100 * summary["between_sd_bound"] / x.mean()
    )
    assert summary["split_half"]["episodes"] == 4


def test_the_legs_r_is_disattenuated_by_both_reliabilities():
    rng = np.random.default_rng(2)
    skill = rng.normal(0, 1, (300, 1))
    normal = skill + rng.normal(0, 2, (300, 8))
    long_legs = skill + rng.normal(0, 2, (300, 8))
    legs = populations.legs_correlation(normal, long_legs)
    rel = legs["reliabilities"]  # about 8 x 0.2 / 2.4 = 0.67 each
    assert legs["test"]["low"] < math.sqrt(rel[0] * rel[1]) < legs["test"]["high"]
    factor = math.sqrt(rel[0] * rel[1])
    assert legs["disattenuated"] == pytest.approx(legs["test"]["estimate"] / factor)
    assert 0.75 < legs["disattenuated"] < 1.25  # the true abilities are the same on both bodies


def test_the_paired_difference_covers_the_truth():
    rng = np.random.default_rng(3)
    covered, truth = 0, 3.0
    for _ in range(200):
        state = rng.normal(0, 5, (50, 6))  # what the shared initial state does to both
        net = 100 + state + rng.normal(0, 4, (50, 6))
        ind = 100 + truth + rng.normal(0, 2, (50, 1)) + state + rng.normal(0, 4, (50, 6))
        diff = populations.mean_network_difference(ind, net)
        covered += diff["test"]["low"] <= truth <= diff["test"]["high"]
    assert 0.91 <= covered / 200 <= 0.99
    assert diff["percent"] == pytest.approx(100 * diff["test"]["estimate"] / net.mean())
    assert diff["se"] == pytest.approx(np.std((ind - net).mean(1), ddof=1) / math.sqrt(50))
    with pytest.raises(ValueError, match="must match"):
        populations.mean_network_difference(ind, net[:, :3])


def test_the_pooled_difference_is_the_inverse_variance_mean():
    estimates, ses = np.array([1.0, 2.0, 4.0]), np.array([1.0, 0.5, 2.0])
    w = 1 / ses**2
    pooled = stats.inverse_variance(estimates, ses)
    assert pooled["estimate"] == pytest.approx((w * estimates).sum() / w.sum())
    assert pooled["se"] == pytest.approx(1 / math.sqrt(w.sum()))
    assert pooled["ci"][1] - pooled["estimate"] == pytest.approx(1.959964 * pooled["se"])
    assert pooled["q"] == pytest.approx((w * (estimates - pooled["estimate"]) ** 2).sum())
    # genomes that agree: no spread between them, random effects = fixed effect
    same = stats.inverse_variance([2.0, 2.0, 2.0], ses)
    assert same["tau2"] == 0.0 and same["random_effects"] == pytest.approx(same["estimate"])
    # genomes far apart: a spread, and a wider random-effects interval
    apart = stats.inverse_variance([0.0, 10.0, 20.0], [1.0, 1.0, 1.0])
    assert apart["tau2"] == pytest.approx(100 - 1)  # DerSimonian-Laird: var of the 3 - se^2
    assert apart["random_effects_se"] > 5 * apart["se"]
    spread = stats.between_genomes([0.0, 10.0, 20.0])
    half = scipy_stats.t.ppf(0.975, 2) * 10 / math.sqrt(3)
    assert spread["ci"] == pytest.approx((10 - half, 10 + half))


def test_a_setting_pools_its_genomes_summaries():
    rng = np.random.default_rng(4)
    summaries = []
    for shift in (1.0, 2.0, 3.0):
        net = rng.normal(100, 5, (40, 4))
        returns = {
            "normal": net + shift + rng.normal(0, 1, (40, 1)),
            "long_legs": rng.normal(80, 5, (40, 4)),
            "mean_network": net,
        }
        summaries.append(populations.genome_summary(returns))
    pooled = populations.pool_setting(summaries)
    d = [s["mean_network"] for s in summaries]
    w = np.array([1 / s["se"] ** 2 for s in d])
    values = np.array([s["test"]["estimate"] for s in d])
    fixed = pooled["mean_network_difference"]["fixed_effect"]
    assert fixed["estimate"] == pytest.approx((w * values).sum() / w.sum())
    assert pooled["mean_network_difference"]["between_genomes"]["mean"] == pytest.approx(
        values.mean()
    )
    # r pooled on Fisher's z with weights n - 3: equal n, the mean of the z's
    rs = [s["legs"]["test"]["estimate"] for s in summaries]
    assert pooled["legs_r"]["fixed_effect"]["estimate"] == pytest.approx(
        math.tanh(np.mean(np.arctanh(rs)))
    )
    assert pooled["legs_r"]["fixed_effect"]["z_se"] == pytest.approx(1 / math.sqrt(3 * 37))


def test_the_profiles_name_committed_checkpoints():
    cpu = populations.PROFILES["cpu"]
    assert len(cpu.genomes) == 6 and {g.settings for g in cpu.genomes} == {"ours", "authors"}
    assert (cpu.n_individuals, cpu.episodes, cpu.episode_length) == (100, 32, 1000)
    for genome in cpu.genomes:
        assert (committed_results() / populations.checkpoint_path(genome, cpu)).exists()
    labels = [populations.genome_label(g) for g in cpu.genomes]
    assert labels[0] == "ant_k64_s0" and labels[-1] == "ant_k64_authors_s2"
    assert populations.eta_s(10.0, 100, 300) == 30.0
    with pytest.raises(ValueError, match="env"):
        populations.run("smoke", ".", env="halfcheetah")


def test_a_smoke_run_resumes_without_evaluating_again(tmp_path, monkeypatch, capsys):
    path = populations.run("smoke", tmp_path)
    assert "populations ant_k64_s0 long_legs (2/6)" in capsys.readouterr().out
    payload = read_results(path)
    results = payload["results"]
    assert results["complete"] and set(results["genomes"]) == {"ant_k64_s0", "ant_k64_s1"}
    for record in results["genomes"].values():
        for part in populations.PARTS:
            assert np.asarray(record["parts"][part]["returns"]).shape == (4, 3)
            assert record["parts"][part]["cpu_time_s"] > 0  # what it cost, pauses not counted
        returns = {p: record["parts"][p]["returns"] for p in populations.PARTS}
        recomputed = json.loads(json.dumps(jsonable(populations.genome_summary(returns))))
        assert record["summary"] == recomputed  # the summary is the stored returns' own
    assert results["pooled"]["ours"]["n_genomes"] == 2
    before = path.read_bytes()

    calls = []
    real = populations.population_returns

    def counted(*args, **kwargs):
        calls.append(kwargs.get("mean_network"))
        return real(*args, **kwargs)

    monkeypatch.setattr(populations, "population_returns", counted)
    populations.run("smoke", tmp_path)
    assert calls == [] and path.read_bytes() == before
    assert "nothing evaluated" in capsys.readouterr().out

    # a part lost (a run killed after writing the others) is the only one evaluated again
    lost = payload["results"]["genomes"]["ant_k64_s1"]["parts"].pop("long_legs")
    path.write_text(json.dumps(payload))
    populations.run("smoke", tmp_path)
    assert calls == [False]
    again = read_results(path)["results"]["genomes"]["ant_k64_s1"]["parts"]["long_legs"]
    assert again["returns"] == lost["returns"]  # the same individuals and initial states

    # a genome whose checkpoint changed since its parts were evaluated (a retrained run
    # under the same name) is evaluated again, every part of it, and only it
    payload = read_results(path)
    genomes = payload["results"]["genomes"]
    kept = genomes["ant_k64_s0"]["checkpoint_sha256"]
    assert len(kept) == 64 and genomes["ant_k64_s1"]["checkpoint_sha256"]
    genomes["ant_k64_s0"]["checkpoint_sha256"] = "0" * 64
    path.write_text(json.dumps(payload))
    calls.clear()
    populations.run("smoke", tmp_path)
    assert len(calls) == len(populations.PARTS)
    assert read_results(path)["results"]["genomes"]["ant_k64_s0"]["checkpoint_sha256"] == kept


def test_the_authors_one_sample_t_leaves_out_the_mean_networks_error_and_welch_counts_it():
    rng = np.random.default_rng(3)
    individuals = 1000 + 30 + 50 * rng.standard_normal((100, 64))  # 30 above the network
    mean_network = 1000 + 400 * rng.standard_normal(200)  # few, noisy episodes
    out = populations.authors_comparison(individuals, mean_network)
    one, welch = out["one_sample"], out["welch"]
    assert one["estimate"] == pytest.approx(welch["estimate"])  # the same difference
    assert out["mean_network_se"] == pytest.approx(400 / math.sqrt(200), rel=0.15)
    # Welch's interval holds the mean network's error: wider, and its t smaller
    width = welch["high"] - welch["low"]
    assert width > 3 * (one["high"] - one["low"]) and abs(welch["t"]) < abs(one["t"]) / 3
    assert welch["low"] < 30 < welch["high"]
    se = math.hypot(out["individuals_se"], out["mean_network_se"])
    assert welch["t"] == pytest.approx(welch["estimate"] / se)


def test_the_regime_genomes_wait_for_their_run_under_the_regime_as_it_now_trains(tmp_path):
    config = populations.REGIME_PROFILES["cpu"]
    labels = [populations.genome_label(g) for g in config.genomes]
    assert labels[:2] == ["ant_regime_k128_s0", "ant_regime_k16_s0"] and len(labels) == 13
    assert (config.n_individuals, config.episodes) == (100, 64)
    by_label = dict(zip(labels, config.genomes, strict=True))
    k64, k128 = by_label["ant_regime_k64_s0"], by_label["ant_regime_k128_s0"]
    assert k64.parts == (*populations.PARTS, *populations.AUTHORS_PARTS)
    assert k128.parts == populations.AUTHORS_PARTS  # our protocol for the 64 types only
    assert populations.checkpoint_path(k64, config) == (
        "rl/checkpoints/ant_regime_k64_s0_cpu.msgpack"
    )
    # a checkpoint under the genome's name from another regime (here: the regime's run as
    # it was evaluated before, on 256 individuals) waits for the run that replaces it
    results = committed_results()
    assert populations.landed(k64, config, results)
    assert populations.landed(k128, config, results)
    ppo, params, normalizer, meta = checkpoints.load(
        results / populations.checkpoint_path(k64, config)
    )
    older = replace(ppo, eval_individuals=256)
    assert not older.trains_as(ppo)
    checkpoints.save(
        tmp_path / populations.checkpoint_path(k64, config),
        TrainResult(older, params, normalizer, meta["eval_steps"], meta["eval_returns"], 1.0, 1.0),
    )
    assert not populations.landed(k64, config, tmp_path)
    queued = populations.queued("cpu", results)
    assert [r.chunks for r in queued.runs[:2]] == [3, 3]
    for genome, run in zip(config.genomes, queued.runs, strict=True):
        waits = "(its training has not landed)" in run.label
        assert waits == (not populations.landed(genome, config, results)), run.label
    # under tmp_path, the older run's checkpoint stands in for the committed one: it waits
    older_listed = populations.queued("cpu", tmp_path).runs[labels.index("ant_regime_k64_s0")]
    assert older_listed.label == "64 types seed 0 (its training has not landed)"
    # the same genome part-way: the state its run keeps after chunk 2, 10^7 steps in
    early = by_label["ant_regime_k64_s0_chunk2"]
    assert populations.checkpoint_path(early, config) == (
        "rl/checkpoints/ant_regime_k64_s0_cpu.chunk2.npz"
    )
    assert populations.genome_steps(early, config) == 9_830_400
    assert populations.genome_steps(k64, config) == 50_000_000
    with pytest.raises(ValueError, match="authors' settings"):
        populations.Genome("ours", 0, regime=True)
    with pytest.raises(ValueError, match="protocol"):
        populations.Genome("authors", 0, protocols=("theirs",))
    with pytest.raises(ValueError, match="part-way"):
        populations.Genome("authors", 0, chunk=2)


def test_pooled_population_rows_find_a_known_advantage_over_the_mean_network():
    """Six synthetic genomes whose individuals beat their mean network by 5 % of its return
    and differ from each other: Figure 5 is reproduced, Figure 4E's r is found."""
    from sgb.experiments import populations

    rng = np.random.default_rng(7)
    genomes = {}
    for settings in ("ours", "authors"):
        for seed in range(3):
            skill = rng.normal(0, 300, (100, 1))
            normal = 2000 + skill + rng.normal(0, 500, (100, 32))
            long_legs = 1500 + skill + rng.normal(0, 500, (100, 32))
            mean_net = normal - 100 + rng.normal(0, 100, (100, 32))
            parts = {"normal": normal, "long_legs": long_legs, "mean_network": mean_net}
            genomes[populations.genome_label(populations.Genome(settings, seed))] = {
                "settings": settings,
                "training_seed": seed,
                "parts": {k: {"returns": v.tolist()} for k, v in parts.items()},
            }
    config = populations.populations_config("cpu")
    summarised = populations.summarise({"genomes": genomes}, config)
    stored = json.loads(json.dumps(jsonable(summarised)))
    results = populations.PopulationsResults.model_validate(stored)
    rows = {(r.key, r.setting.split(",")[1]): r for r in population_runs.populations_rows(results)}
    for who in (" our genome", " the authors' genome"):
        assert rows["fig5.population_beats_mean", who].verdict in verdicts.IN_DIRECTION
        assert rows["fig4e.r_legs", who].verdict in verdicts.IN_DIRECTION
        # individuals 15 % of the return apart (SD 300 of 2000) differ by more than 1 %
        assert rows["title.variability", who].verdict == verdicts.LARGER


def test_regime_population_rows_tell_the_two_protocols_apart():
    """Two synthetic 64-type genomes read back through JSON, the first under both
    protocols: its individuals beat the mean network by 5 % on the same states, and under
    sampled actions by 2 % with a mean network so noisy that only the one-sample t (which
    takes its mean as exact) calls it; individuals 15 % of the return apart differ by more
    than 1 %, each genome and both pooled with the genome as the unit."""
    from sgb.experiments import populations

    rng = np.random.default_rng(11)
    genomes = {}
    for seed in (0, 1):
        skill = rng.normal(0, 300, (100, 1))
        normal = 2000 + skill + rng.normal(0, 300, (100, 64))
        parts = {
            "sampled": 2040 + skill + rng.normal(0, 300, (100, 64)),
            "long_legs_sampled": 1500 + skill + rng.normal(0, 300, (100, 64)),
            "mean_network_sampled": rng.normal(2000, 2000, (16, 1)),
        }
        if seed == 0:
            parts |= {
                "normal": normal,
                "long_legs": 1500 + skill + rng.normal(0, 300, (100, 64)),
                "mean_network": normal - 100 + rng.normal(0, 50, (100, 64)),
            }
        genomes[f"k64_s{seed}"] = {
            "cell_types": 64,
            "training_seed": seed,
            "trained_steps": 50_000_000,
            "parts": {k: {"returns": v.tolist()} for k, v in parts.items()},
            "summary": populations.genome_summary(parts),
        }
    stored = json.loads(json.dumps(jsonable({"genomes": genomes})))
    results = populations.RegimePopulationsResults.model_validate(stored)
    rows = population_runs.regime_population_rows(results)
    fig5 = [r for r in rows if r.key == "fig5.population_beats_mean"]
    assert len(fig5) == 5  # paired, one-sample and Welch for seed 0; the last two for seed 1
    assert fig5[0].verdict in verdicts.IN_DIRECTION
    assert fig5[0].test.estimate == pytest.approx(5.0, abs=0.5)  # % of the mean network
    one_sample, welch = fig5[1:3]
    assert one_sample.test.p < 0.05 < welch.test.p
    assert welch.verdict == verdicts.INCONCLUSIVE
    legs = [r for r in rows if r.key == "fig4e.r_legs"]
    assert len(legs) == 3 and all(r.verdict in verdicts.IN_DIRECTION for r in legs)
    assert all(r.test.low > 0.5 for r in legs)
    variability = [r for r in rows if r.key == "title.variability.regime"]
    assert [r.verdict for r in variability] == [verdicts.LARGER] * 4
    pooled = variability[-1]
    assert "2 genomes pooled" in pooled.setting and "sampled actions" in pooled.setting
    each = [r.test.estimate for r in variability[:3] if "sampled" in r.setting]
    assert pooled.test.estimate == pytest.approx(np.mean(each))
    texts = population_runs.regime_populations(SimpleNamespace(results=results))
    assert texts["regime_pop_design"] == (
        "2 of the 13 genomes (64 types seed 0, 64 types seed 1), each 100 individuals x 64 episodes"
    )
    assert texts["regime_pop_legs"].count("**") == 2 * len(legs)
    assert texts["regime_pop_welch"].count("; ") == 1  # one Welch row a genome
    assert texts["regime_pop_retest"].startswith("64 types seed 0: r = ")
    # both genomes' individuals differ under sampled actions, seed 0's under deterministic
    # too; every r lies above 0; only seed 0's paired 5 % lies above its mean network
    assert texts["regime_pop_answer"] == (
        "individuals of one genome can be told apart under sampled actions (the authors' "
        f"protocol) in 2 of 2 genomes (64 types, seed 0: {variability[1].ours} % of the "
        f"return; 64 types, seed 1: {variability[2].ours} % of the return) and under "
        "deterministic actions (ours) in 1 of 1 genomes (64 types, seed 0: "
        f"{variability[0].ours} % of the return). Figure 4E's r between the bodies lies "
        "above 0 in 3 of 3 measurements (genome and protocol) and below 0 in 0; Figure 5's "
        "individuals lie above their mean network in 1 of 3 and below it in 0"
    )
    texts = population_runs.regime_populations(None)
    assert set(texts.values()) == {population_runs.NOT_RUN}
    # a genome part-way that does not yet walk (mean return about -7): a % of its return says
    # nothing, so it adds no Figure 5 and no variability row; Figure 4E's r (scale-free)
    # stays. Its individuals play nearly the same episodes' returns in another order: no
    # reliability, so what would decide Figure 4E is their SD, in return units
    episodes = rng.normal(-7, 20, 64)
    crawl = {
        "sampled": np.array([rng.permutation(episodes) for _ in range(100)])
        + rng.normal(0, 1, (100, 64)),
        "long_legs_sampled": rng.normal(-11, 20, (100, 64)),
        "mean_network_sampled": rng.normal(-7, 20, (16, 1)),
    }
    genomes["k64_s0_chunk2"] = genomes["k64_s0"] | {
        "trained_steps": 9_830_400,
        "parts": {k: {"returns": v.tolist()} for k, v in crawl.items()},
        "summary": populations.genome_summary(crawl),
    }
    stored = json.loads(json.dumps(jsonable({"genomes": genomes})))
    results = populations.RegimePopulationsResults.model_validate(stored)
    added = [
        r
        for r in population_runs.regime_population_rows(results)
        if "9.83 x 10^6 steps" in r.setting
    ]
    assert [r.key for r in added] == ["fig4e.r_legs"]
    assert added[0].decide.startswith("individuals that differ: their SD is at most ")
    assert added[0].decide.endswith(" (return units; the mean return, -6, is not positive)")
    # a 64-type genome part-way through its parts (ours come first, no sampled one yet)
    # is a valid file that adds no row
    genomes["k64_s2"] = {
        "cell_types": 64,
        "training_seed": 2,
        "trained_steps": 50_000_000,
        "parts": {"normal": {"returns": rng.normal(2000, 300, (100, 64)).tolist()}},
    }
    stored = json.loads(json.dumps(jsonable({"genomes": genomes})))
    partway = populations.RegimePopulationsResults.model_validate(stored)
    assert population_runs.regime_population_rows(
        partway
    ) == population_runs.regime_population_rows(results)
    # the same genome at two points: individuals without a skill of their own part-way,
    # 15 % of the return apart at the end, told apart only there
    course = population_runs.regime_populations(SimpleNamespace(results=results))
    early, late = course["regime_pop_training"].split("; after ")
    assert early.startswith("64 types seed 0: after 9.83 x 10^6 steps, mean return -6")
    assert late.endswith("(individuals told apart only after 5 x 10^7 steps)")


def test_genomes_pooled_only_where_their_sds_differ():
    """Two genomes whose individuals cannot be told apart (SD between 0 each) give no
    pooled row, where a t over genomes is undefined; two that differ give the mean."""
    rows = population_runs.pooled_variability_rows(
        "title.variability.regime",
        {("alike", 100, 64, None): [0.0, 0.0], ("apart", 100, 64, None): [0.5, 1.5]},
    )
    (row,) = rows
    assert row.setting.startswith("apart, 2 genomes pooled")
    assert row.test.estimate == pytest.approx(1.0)
