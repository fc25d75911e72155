"""Innate starts for further learning (chapter 6): a fine-tuned run starts where its
developed network plays, selection and scoring use other initial states, the curve's
scores, and both experiments end to end on cheap problems, resuming without redoing."""

import dataclasses
import json
from dataclasses import replace

import jax
import numpy as np
import pytest
from reach import EPISODE, SPEC, reach_config

from sgb.experiments import fig2, innate_start, innate_start_supervised
from sgb.provenance import read_results
from sgb.rl import checkpoints
from sgb.rl.agent import NetworkConfig
from sgb.rl.finetune import individual_key, plain_actor, plain_network
from sgb.rl.population import population_keys, population_returns
from sgb.rl.ppo import Start, TrainResult, evaluate, init_state, train
from sgb.rl.sweep import sweep_config
from sgb.rl.trainer import make_trainer

GENOME = reach_config(4, network=NetworkConfig(hidden=(16, 16), cell_types=4, rho_init=-1.0))
# the fine-tuning PPO: vanilla, of the genome's widths, a few short chunks
FINETUNE = reach_config(
    network=plain_network(GENOME.network),
    total_steps=4 * 8 * 4,
    num_envs=8,
    unroll_length=4,
    num_minibatches=2,
    num_evals=4,
    eval_individuals=3,
)


def _genome():
    """A random SGB genome on Reach (untrained: a genome all the same) and its normalizer,
    made as if from some observations so that it is not the identity."""
    ts = init_state(GENOME, seed=3)
    normalizer = ts.normalizer._replace(
        count=np.float32(50.0), mean=np.array([0.1, -0.2], np.float32), m2=np.ones(2, np.float32)
    )
    return ts.params, jax.tree_util.tree_map(jax.numpy.asarray, normalizer)


def test_the_start_replaces_the_actor_and_normalizer_and_nothing_else():
    params, normalizer = _genome()
    actor = plain_actor(GENOME, params.actor)
    fresh = init_state(FINETUNE, seed=1)
    started = init_state(FINETUNE, seed=1, initial=Start(actor, normalizer))
    for got, want in ((started.params.actor, actor), (started.normalizer, normalizer)):
        jax.tree_util.tree_map(np.testing.assert_array_equal, got, want)
    jax.tree_util.tree_map(
        np.testing.assert_array_equal, started.params.critic, fresh.params.critic
    )
    jax.tree_util.tree_map(np.testing.assert_array_equal, started.env_state, fresh.env_state)
    with pytest.raises(ValueError, match="shapes"):
        init_state(FINETUNE, seed=1, initial=Start(params.actor, normalizer))  # not vanilla


def test_a_run_from_the_mean_network_starts_exactly_where_the_mean_network_plays(tmp_path):
    params, normalizer = _genome()
    initial = Start(plain_actor(GENOME, params.actor), normalizer)
    config = innate_start.InnateStartConfig(("genome",), FINETUNE, (1,), 4, 2, (0.0, 0.5, 1.0))
    record = innate_start.finetune_run(config, 1, initial, tmp_path / "run.state.npz")
    mean_network = population_returns(
        SPEC,
        GENOME.network,
        params.actor,
        normalizer,
        FINETUNE.eval_individuals,
        1,
        EPISODE,
        seed=1 + innate_start.START_EVAL_SEED,
        mean_network=True,
    )
    assert record["eval_returns"][0] == float(np.mean(mean_network))
    assert record["eval_steps"] == [0, 32, 64, 96, 128]
    # train's evaluations after chunk i use seed + TRAIN_EVAL_SEED + i, as the seeds say
    result = train(FINETUNE, 1, progress=False, initial=initial)
    assert record["eval_returns"][1:] == result.eval_returns
    last = innate_start.evaluation_seeds(FINETUNE, 1)[-1]
    assert evaluate(FINETUNE, result.params, result.normalizer, last) == result.eval_returns[-1]


def test_the_plain_actor_of_an_individual_is_that_individual():
    params, normalizer = _genome()
    n, seed = 5, 7
    genome = population_returns(SPEC, GENOME.network, params.actor, normalizer, n, 2, 10, seed)
    agent = make_trainer(GENOME.step_settings()).agent
    keys = np.stack([individual_key(seed, n, i) for i in range(n)])
    phenotypes = agent.actor.layers(params.actor, jax.vmap(agent.actor.draw)(keys))
    plain = plain_network(GENOME.network)
    for i in (0, 3):
        actor = plain_actor(GENOME, params.actor, individual_key(seed, n, i))
        for (kernel, bias), name in zip(phenotypes, agent.actor.names, strict=True):
            # drawn layers have a leading axis of individuals; the deterministic output not
            own = actor["params"][name]
            np.testing.assert_array_equal(own["kernel"], kernel[i] if kernel.ndim == 3 else kernel)
            np.testing.assert_array_equal(own["bias"], bias[i] if bias.ndim == 2 else bias)
        mine = population_returns(SPEC, plain, actor, normalizer, n, 2, 10, seed)
        # the same weights as plain matrices rather than a batch: equal to float rounding
        np.testing.assert_allclose(mine[i], genome[i], rtol=1e-5)


def test_the_selection_plays_initial_states_no_evaluation_plays():
    config = innate_start.PROFILES["cpu"]
    picked = population_keys(
        config.n_individuals, config.selection_episodes, innate_start.SELECTION_SEED
    )
    selection = {tuple(k) for k in np.asarray(picked[1]).reshape(-1, 2)}
    assert len(selection) == config.n_individuals * config.selection_episodes
    for seed in config.seeds:
        seeds = innate_start.evaluation_seeds(config.ppo, seed)
        assert len(seeds) == config.ppo.num_evals + 1
        for s in seeds:
            scored = population_keys(config.ppo.eval_individuals, 1, s)[1]
            assert selection.isdisjoint(tuple(k) for k in np.asarray(scored).reshape(-1, 2))
    with pytest.raises(ValueError, match="selection"):  # 9_999 + 10_000 + 1 is its seed
        innate_start.InnateStartConfig(config.genomes, config.ppo, (9_999,), 10_000)


def test_the_curve_is_scored_by_its_area_and_its_returns_at_fractions_of_the_budget():
    scores = innate_start.curve_scores([0, 10, 20, 30, 40], [0.0, 2.0, 2.0, 4.0, 4.0], (0, 0.5, 1))
    assert scores["auc"] == pytest.approx((10 + 20 + 30 + 40) / 40)
    assert scores["return_at"] == {"0": 0.0, "0.5": 2.0, "1": 4.0}
    with pytest.raises(ValueError, match="evaluation"):
        innate_start.InnateStartConfig(("g",), FINETUNE, fractions=(0.3,))


def test_the_profiles_fine_tune_figure_3s_ppo_on_long_legs():
    cpu = innate_start.PROFILES["cpu"]
    fig3 = sweep_config("ant", "cpu").ppo
    assert cpu.ppo == replace(
        fig3, env=replace(fig3.env, variant="long_legs"), total_steps=5_000_000, num_evals=8
    )
    assert len(innate_start.planned_runs(cpu)) == 3 * (1 + 3 * 3)
    assert cpu.genomes == (
        "ant_k64_s0_cpu.msgpack",
        "ant_k64_authors_s0_cpu.msgpack",
        "ant_k64_rho-3_s0_cpu.msgpack",
    )


def test_the_experiment_selects_fine_tunes_and_resumes_without_redoing(tmp_path, monkeypatch):
    params, normalizer = _genome()
    genome = TrainResult(GENOME, params, normalizer, [1], [0.0], 0.0, 0.0)
    checkpoints.save(tmp_path / "rl" / "checkpoints" / "reach_k4_s0_cpu.msgpack", genome)
    config = innate_start.InnateStartConfig(("reach_k4_s0_cpu.msgpack",), FINETUNE, (1,), 6, 2)
    monkeypatch.setattr(innate_start, "PROFILES", {"smoke": config})
    path = innate_start.run("smoke", tmp_path)
    results = read_results(path)["results"]
    assert results["complete"]
    [selection] = results["selections"]
    means = population_returns(
        SPEC,
        GENOME.network,
        params.actor,
        normalizer,
        6,
        2,
        EPISODE,
        seed=innate_start.SELECTION_SEED,
    ).mean(1)
    np.testing.assert_allclose(selection["individual_means"], means, atol=1e-3)
    assert selection["best"] == int(np.argmax(means))
    runs = {r["start"]: r for r in results["runs"]}
    assert runs["fresh"]["genome"] is None and runs["mean"]["genome"] == "reach_k4_s0_cpu"
    assert runs["best"]["individual"] == selection["best"] and runs["random"]["individual"] == 1
    assert runs["best"]["selection_return"] == selection["individual_means"][selection["best"]]
    assert {r["eval_steps"][-1] for r in runs.values()} == {128}
    assert all({"wall_time_s", "git_commit", "auc", "return_at"} <= set(r) for r in runs.values())
    assert not list((tmp_path / "rl" / "innate_start").iterdir())  # no training state left
    before = path.read_bytes()

    def redone(*args, **kwargs):
        raise AssertionError("a finished run or selection was done again")

    monkeypatch.setattr(innate_start, "finetune_run", redone)
    monkeypatch.setattr(innate_start, "select", redone)
    assert innate_start.run("smoke", tmp_path).read_bytes() == before


_SMOKE = fig2.PROFILES["smoke"]["digits"]["sweep"]
# a wide spread, so that the individuals differ
_SGB = dataclasses.replace(_SMOKE.sgb, epochs=10, eval_individuals=3, rho_init=-1.5)
SUPERVISED = innate_start_supervised.SupervisedStartConfig(
    dataset="digits",
    sweep=dataclasses.replace(_SMOKE, hidden=(32,), sgb=_SGB),
    ratio=4.0,
    seeds=(0,),
    budgets=(0, 3, 30),
)


def test_a_genome_of_five_classes_hands_its_hidden_layers_to_the_other_five(tmp_path, monkeypatch):
    """The genome learns digits 0-4 and knows them; its individuals, its mean network and
    fresh networks then learn digits 5-9, every start from the genome with a fresh
    network's output layer and its own hidden layers, and every network learns."""
    monkeypatch.setattr(innate_start_supervised, "PROFILES", {"smoke": SUPERVISED})
    path = innate_start_supervised.run("smoke", tmp_path, progress=False)
    results = read_results(path)["results"]
    [record] = results["records"]
    runs = record["runs"]
    assert results["genome_classes"] == [0, 1, 2, 3, 4]
    assert [r["start"] for r in runs] == ["mean"] + ["individual"] * 3 + ["fresh"] * 3
    assert all(r["steps"] == [0, 3, 30] for r in runs)
    assert record["innate"]["mean_network"] > 0.6  # on its own classes
    fresh = [r["accuracy"][0] for r in runs[4:]]
    assert len(set(fresh)) == 3  # three initialisations
    assert all(r["accuracy"][-1] > r["accuracy"][0] + 0.2 for r in runs)
    summary = {row["start"]: row for row in results["summary"]}
    assert summary["mean"]["accuracy"] == runs[0]["accuracy"]
    a, b = ({"params": {"dense_0": {"kernel": v}, "dense_1": {"kernel": -v}}} for v in (1, 2))
    assert innate_start_supervised.with_head(a, b)["params"] == {
        "dense_0": {"kernel": 1},
        "dense_1": {"kernel": -2},
    }
    before = path.read_bytes()
    monkeypatch.setattr(innate_start_supervised, "run_seed", lambda *a: pytest.fail("redone"))
    assert innate_start_supervised.run("smoke", tmp_path, progress=False).read_bytes() == before
    assert json.loads(before)["provenance"]["wall_time_s"] == record["wall_time_s"]
