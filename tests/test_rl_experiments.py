"""Figure 3-5 experiment logic: sweep summaries, correlations, paired tests, profiles."""

import re
import threading
from collections import Counter
from dataclasses import replace

import numpy as np
import pytest
from reach import EPISODE, SHARED_STEP, shared_step_config

from sgb.experiments import fig3, fig4_5, get_experiment, regime_peer, rl_spread
from sgb.paths import committed_results
from sgb.provenance import read_results
from sgb.rl import protocols
from sgb.rl.agent import NetworkConfig
from sgb.rl.protocols import population_config
from sgb.rl.regime_runs import RUNS, RegimeRun
from sgb.rl.regimes import with_settings
from sgb.rl.runs import checkpoint_name
from sgb.rl.sweep import sweep_config


def test_summary_divides_by_the_mean_vanilla_return():
    runs = [
        {"settings": "ours", "cell_types": None, "seed": 0, "final_return": 100.0},
        {"settings": "ours", "cell_types": None, "seed": 1, "final_return": 300.0},
        {"settings": "ours", "cell_types": 16, "seed": 0, "final_return": 50.0},
        {"settings": "ours", "cell_types": 16, "seed": 1, "final_return": 150.0},
        {"settings": "authors", "cell_types": 16, "seed": 0, "final_return": 400.0},
    ]
    rows = {(r["settings"], r["cell_types"]): r for r in fig3.summarise_cell_types(runs)}
    assert rows["ours", None]["fraction"] == pytest.approx(1.0)
    assert rows["ours", 16]["fraction"] == pytest.approx(0.5)
    assert rows["ours", 16]["sem_fraction"] == pytest.approx(50.0 / 200.0)  # sem(50, 150) = 50
    assert rows["authors", 16]["fraction"] == pytest.approx(2.0)  # the one vanilla is shared
    assert rows["authors", 16]["n_seeds"] == 1


def test_sweep_trains_vanilla_once_and_each_sgb_count_under_each_settings():
    config = sweep_config("ant", "cpu")
    runs = fig3.sweep_runs(config)
    seeds = Counter((s, k) for s, k, _ in runs)
    assert seeds[("ours", None)] == seeds[("ours", 128)] == seeds[("authors", 16)] == 10
    assert seeds[("ours", 64)] == seeds[("authors", 32)] == seeds[("ours_typed_inputs", 16)] == 5
    assert len(runs) == len(set(runs)) == 10 * 5 + 5 * 4 + 5 * 2
    assert {(s, k) for s, k, _ in runs if k is None} == {("ours", None)}
    assert [seed for *_, seed in runs] == sorted(seed for *_, seed in runs)  # seed by seed
    net16 = replace(config.ppo, network=NetworkConfig(cell_types=16))
    authors = with_settings(net16, "authors")
    assert authors.kl_coef == 0.0 and authors.network.rho_init == -7.0
    assert authors.network.typed_inputs and authors.network.sgb_output
    assert authors.network.prior == "gaussian"
    assert with_settings(config.ppo, "authors") == config.ppo  # vanilla has no genome
    # the ablations swap the input typing and nothing else
    untyped = with_settings(net16, "authors_untyped_inputs")
    assert untyped == replace(authors, network=replace(authors.network, typed_inputs=False))
    typed = with_settings(net16, "ours_typed_inputs")
    assert typed == replace(net16, network=replace(net16.network, typed_inputs=True))
    names = {checkpoint_name("ant", k, seed, "cpu", s) for s, k, seed in runs}
    assert len(names) == len(runs)


def test_the_one_checkpoint_name_gives_every_committed_checkpoint_its_name():
    """Figure 3's, the spread sweep's and the regime's committed runs (and the regime's peer
    runs, apart in ``peer/``): each run's recorded
    checkpoint is the name ``checkpoint_name`` makes from its config, and every committed
    checkpoint, and every one a results file names, is the name of a run of a cpu config."""
    results = committed_results()
    recorded = {}
    for env in ("ant", "halfcheetah"):
        runs = read_results(results / "rl" / f"fig3_{env}_cpu.json")["results"]["runs"]
        planned = set(fig3.sweep_runs(sweep_config(env, "cpu")))
        for r in runs:
            assert (r["settings"], r["cell_types"], r["seed"]) in planned
            name = checkpoint_name(env, r["cell_types"], r["seed"], "cpu", r["settings"])
            recorded[name] = r["checkpoint"]
    spread = rl_spread.PROFILES["cpu"]
    for r in read_results(results / "rl" / "spread_ant_cpu.json")["results"]["runs"]:
        types = spread.ppo.network.cell_types
        name = checkpoint_name("ant", types, r["seed"], "cpu", rho_init=r["rho_init"])
        recorded[name] = r["checkpoint"]
    for r in read_results(results / "rl" / "regime_ant_cpu.json")["results"]["runs"]:
        run = RegimeRun(r["cell_types"], r["seed"], r["genome"])
        assert run in RUNS["cpu"].runs
        recorded[run.checkpoint("cpu")] = r["checkpoint"]
    assert recorded and all(made == kept for made, kept in recorded.items())
    assert "ant_regime_vanilla_s0_cpu.msgpack" in recorded
    made = {
        checkpoint_name(e, k, seed, "cpu", s)
        for e in ("ant", "halfcheetah")
        for s, k, seed in fig3.sweep_runs(sweep_config(e, "cpu"))
    }
    made |= {
        checkpoint_name("ant", spread.ppo.network.cell_types, seed, "cpu", rho_init=rho)
        for rho in spread.rho_inits
        for seed in spread.seeds
    }
    made |= {r.checkpoint("cpu") for r in RUNS["cpu"].runs}
    made |= {r.checkpoint("cpu") for r in regime_peer.PROFILES["cpu"].runs}  # in peer/
    committed = {p.name for p in (results / "rl" / "checkpoints").rglob("*.msgpack")}
    named = {
        name
        for path in results.rglob("*.json")
        for name in re.findall(r"[\w.-]+_s\d+_(?:smoke|cpu|paper)\.msgpack", path.read_text())
    }
    assert committed and committed <= made
    assert named <= committed


def test_correlation_and_paired_test_on_known_populations():
    rng = np.random.default_rng(0)
    skill = rng.normal(size=60)
    returns = {
        "normal": {"individuals": skill[:, None] + 0.1 * rng.normal(size=(60, 3))},
        "long_legs": {"individuals": skill[:, None] + 0.1 * rng.normal(size=(60, 3))},
        "slippery": {"individuals": rng.normal(size=(60, 3))},
        "low_gravity": {"individuals": rng.normal(size=(60, 3))},
    }
    returns["normal"]["mean_network"] = returns["normal"]["individuals"] - 1.0
    assert protocols.compare(returns, "normal", "long_legs")["r"] > 0.9
    assert abs(protocols.compare(returns, "slippery", "low_gravity")["r"]) < 0.4
    test = protocols.individuals_vs_mean(returns)
    assert test["t"] > 10 and test["dof"] == 59


def test_registered_profiles():
    for name in ("fig3", "fig4", "fig5", "spread"):
        assert set(get_experiment(name).profiles) == {"smoke", "cpu", "paper"}
    assert get_experiment("fig3").profiles["cpu"]["halfcheetah"] == sweep_config(
        "halfcheetah", "cpu"
    )
    assert get_experiment("fig4").profiles["smoke"].mean_network_conditions == ()
    assert get_experiment("fig5").profiles["smoke"].conditions == ("normal",)
    paper = sweep_config("ant", "paper")
    assert paper.ppo.num_envs == 2048 and paper.ppo.total_steps == 50_000_000
    assert paper.cell_types == (None, 128, 64, 48, 32, 16) and len(paper.seeds) == 5
    assert population_config("cpu").n_individuals == 100


def test_bad_env_raises():
    with pytest.raises(ValueError, match="env"):
        sweep_config("hopper", "cpu")
    with pytest.raises(ValueError, match="env"):
        fig4_5.run_fig4("smoke", ".", env="halfcheetah")


def test_spread_summary_pairs_each_seed_with_its_own_mean_network():
    def run(rho, seed, individuals, mean_network):
        return {
            "rho_init": rho,
            "sigma_init": float(np.log1p(np.exp(rho))),
            "seed": seed,
            "sigma_trained": 0.1,
            "individuals_mean": individuals,
            "individuals_sd": 2.0,
            "mean_network_mean": mean_network,
        }

    # seeds differ a lot in level, but each population is 5 above its own mean network
    runs = [run(-5.0, s, 100.0 * s + 5.0, 100.0 * s) for s in range(3)]
    runs += [run(-2.0, 0, 40.0, 50.0), run(-2.0, 1, 45.0, 50.0)]
    narrow, wide = rl_spread.summarise_spread(runs)
    assert narrow["advantage"] == 5.0 and narrow["sem_advantage"] == 0.0
    assert narrow["n_seeds"] == 3 and wide["n_seeds"] == 2
    assert wide["advantage"] == -7.5 and np.isclose(wide["sem_advantage"], 2.5)
    for r, t in zip(runs, (0.5, -1.25, 2.0, -3.0, -4.0), strict=True):
        r |= {"checkpoint": "", "paired_test": {"t": t, "p": 0.5}}
    runs[-1]["sigma_trained"] = 0.19  # the wide group's larger change: 0.19 against 0.127
    results = {"runs": runs, "summary": rl_spread.summarise_spread(runs)}  # as the file holds
    prose = rl_spread.spread_prose(rl_spread.SpreadResults.model_validate(results))
    assert prose["spread0_advantage"] == "+5 ± 0" and prose["spread1_advantage"] == "-8 ± 2"
    assert prose["spread0_t"] == "+0.50, -1.25, +2.00" and prose["spread1_t"] == "-3.00, -4.00"
    assert prose["spread1_individuals"] == "42" and prose["spread1_mean_network"] == "50"
    sigma_wide = float(np.log1p(np.exp(-2.0)))
    assert prose["spread1_sigma_change"] == f"{100 * abs(0.19 / sigma_wide - 1):.1f} %"


@SHARED_STEP
def test_spread_run_trains_and_evaluates_wider_genomes(tmp_path, monkeypatch):
    # the sweep on the cheap Reach environment (the Ant's smoke profile runs in CI)
    population = protocols.PopulationConfig(
        "", n_individuals=16, episodes=8, episode_length=EPISODE, conditions=("normal",)
    )
    config = rl_spread.SpreadConfig(
        rho_inits=(-5.0, -2.0),
        seeds=(0,),
        ppo=shared_step_config(eval_individuals=4),
        population=population,
    )
    monkeypatch.setitem(rl_spread.PROFILES, "smoke", config)
    summary = read_results(rl_spread.run("smoke", tmp_path))["results"]["summary"]
    narrow, wide = summary
    assert narrow["rho_init"] < wide["rho_init"]
    assert wide["sigma_trained"] > 10 * narrow["sigma_trained"]
    # wider genomes make more diverse individuals
    assert wide["individuals_sd"] > narrow["individuals_sd"]


def test_the_run_loop_trains_the_runs_no_other_process_holds_and_writes_after_each(
    tmp_path, monkeypatch, capsys
):
    from sgb import runlock
    from sgb.rl import runs as rl_runs

    events = []

    def trained(ppo, seed, checkpoint, profile, label, keep):
        events.append(label)
        return checkpoint.name != "reused"

    monkeypatch.setattr(rl_runs, "trained_run", trained)
    planned = [(name, None, 0, tmp_path / name) for name in ("a", "held", "reused", "b")]
    taken, done = threading.Event(), threading.Event()

    def other():  # another holder: a thread of this process is refused a lock as one
        with runlock.claim(tmp_path / "held"):
            taken.set()
            done.wait()

    holder = threading.Thread(target=other)
    holder.start()
    taken.wait()
    try:
        written = rl_runs.train_runs(planned, "smoke", lambda: events.append("write") or "file")
    finally:
        done.set()
        holder.join()
    assert written == "file"
    assert events == ["a (1/4)", "write", "reused (3/4)", "b (4/4)", "write", "write"]
    assert "held (2/4): another process is training it" in capsys.readouterr().out
