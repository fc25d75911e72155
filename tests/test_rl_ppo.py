"""PPO and populations on a cheap environment: learning, individuals, checkpoints, GAE."""

import json
from dataclasses import replace

import brax.envs
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from brax.envs.base import State
from interrupt import killed_at_chunk
from reach import (
    EPISODE,
    SGB_TYPES,
    SHARED_STEP,
    SPEC,
    Reach,
    reach_config,
    shared_step_config,
)
from scipy import stats as scipy_stats

from sgb import genome
from sgb.divergence import TrainingDiverged
from sgb.genome import layer_sigmas
from sgb.rl import checkpoints
from sgb.rl.agent import (
    MLP,
    NetworkConfig,
    forward,
    make_agent,
    tanh_gaussian_entropy,
    tanh_gaussian_log_prob,
)
from sgb.rl.envs import EnvSpec
from sgb.rl.normalizer import init_normalizer, update
from sgb.rl.population import population_returns
from sgb.rl.ppo import init_state, train
from sgb.rl.protocols import PopulationConfig, authors_protocol
from sgb.rl.trainer import make_trainer


@pytest.mark.parametrize(
    ("cell_types", "threshold"),
    [(None, -8.0), pytest.param(SGB_TYPES, -14.0, marks=SHARED_STEP)],
)
def test_ppo_learns_reach(cell_types, threshold):
    result = train(reach_config(cell_types), seed=0, progress=False)
    # standing still earns about -21; SGB hidden layers with 16 types learn more slowly
    assert result.eval_returns[-1] > threshold, result.eval_returns
    assert result.eval_steps[-1] == 2 * (2**15 // (64 * 8) // 2) * 64 * 8


class WeakReach(Reach):
    """Reach whose step, like Brax's Ant, returns a weakly typed ``done`` (never 1 here)."""

    def step(self, state: State, action: jax.Array) -> State:
        state = super().step(state, action)
        return state.replace(done=jnp.where(state.reward < -10.0, 1.0, 0.0))


brax.envs.register_environment("weak_reach", WeakReach)


def test_the_training_step_compiles_once_for_runs_that_differ_only_outside_it():
    # Left as they are, weakly typed leaves of the environment state would make the second
    # chunk of iterations compile the whole training step again.
    network = NetworkConfig(hidden=(8,), cell_types=2)
    config = reach_config(
        env=EnvSpec("weak_reach", "none"),
        network=network,
        total_steps=3 * 8 * 4,
        num_envs=8,
        unroll_length=4,
        num_minibatches=2,
        num_evals=3,
        eval_individuals=2,
    )
    train(config, seed=0, progress=False)
    trainer = make_trainer(config.step_settings())
    assert trainer.iterations._cache_size() == 1
    # the initial spread, the length and the evaluations of a run do not enter the step
    wider = replace(network, rho_init=-1.0)
    other = replace(config, network=wider, total_steps=64, num_evals=2, eval_individuals=3)
    train(other, 0, False)
    assert make_trainer(other.step_settings()) is trainer
    assert trainer.iterations._cache_size() == 1
    # a setting the step reads is a trainer of its own
    assert make_trainer(replace(config, clip=0.2).step_settings()) is not trainer


def _actor(config):
    return make_agent(config.network, 2, 1).actor


def _sgb_params(rho_init=-1.0):
    network = NetworkConfig(hidden=(32, 32), cell_types=4, rho_init=rho_init)
    config = reach_config(4, network=network)
    return config, init_state(config, seed=3)


def test_same_key_same_individual_and_return():
    config, ts = _sgb_params()
    actor = _actor(config)
    keys = jax.random.split(jax.random.PRNGKey(0), 2)
    a = actor.layers(ts.params.actor, jax.vmap(actor.draw)(keys))
    b = actor.layers(ts.params.actor, jax.vmap(actor.draw)(keys))
    for (ka, _), (kb, _) in zip(a, b, strict=True):
        np.testing.assert_array_equal(ka, kb)
    assert not np.allclose(a[0][0][0], a[0][0][1])  # two keys, two individuals
    args = (SPEC, config.network, ts.params.actor, ts.normalizer, 5, 2, EPISODE)
    np.testing.assert_array_equal(
        population_returns(*args, seed=7), population_returns(*args, seed=7)
    )


def test_hundred_keys_give_hundred_returns():
    config, ts = _sgb_params()
    returns = population_returns(
        SPEC, config.network, ts.params.actor, ts.normalizer, 100, 1, EPISODE, seed=1
    )
    assert returns.shape == (100, 1)
    assert len(np.unique(returns)) == 100
    # the mean network plays the same initial states: one network, spread from states only
    mean_net = population_returns(
        SPEC,
        config.network,
        ts.params.actor,
        ts.normalizer,
        100,
        1,
        EPISODE,
        seed=1,
        mean_network=True,
    )
    assert mean_net.shape == (100, 1) and not np.array_equal(mean_net, returns)


def test_the_authors_figure_5_protocol_samples_actions():
    config, ts = _sgb_params()
    args = (SPEC, config.network, ts.params.actor, ts.normalizer, 6, 2, EPISODE)
    sampled = population_returns(*args, seed=4, stochastic=True)
    np.testing.assert_array_equal(sampled, population_returns(*args, seed=4, stochastic=True))
    assert not np.allclose(sampled, population_returns(*args, seed=4))
    population = PopulationConfig(
        "", n_individuals=12, episode_length=EPISODE, sampled_episodes=3, mean_network_episodes=40
    )
    out = authors_protocol(config, ts.params.actor, ts.normalizer, population)
    assert out["individuals"].shape == (12, 3) and out["mean_network"].shape == (40,)
    expected = scipy_stats.ttest_1samp(out["individuals"].mean(axis=1), out["mean_network"].mean())
    assert out["t"] == pytest.approx(expected.statistic) and out["dof"] == 11


def test_ratio_is_one_for_the_collecting_individual():
    """Rebuilding each unroll's individual from its kept noise reproduces the behaviour policy."""
    config, ts = _sgb_params()
    trainer = make_trainer(config.step_settings())
    ts, data = trainer.unroll(ts)
    layers = trainer.agent.actor.layers(ts.params.actor, data.individual.actor)
    loc, scale = trainer.agent.policy(layers, ts.normalizer, data.obs)
    np.testing.assert_allclose(tanh_gaussian_log_prob(data.u, loc, scale), data.log_prob, atol=1e-4)


def test_normalizer_matches_numpy():
    rng = np.random.default_rng(1)
    a, b = rng.normal(2.0, 3.0, (50, 3)), rng.normal(-1.0, 0.5, (30, 3))
    mask = np.ones(30)
    mask[20:] = 0
    norm = update(update(init_normalizer(3), jnp.asarray(a), jnp.ones(50)), jnp.asarray(b), mask)
    seen = np.concatenate([a, b[:20]])
    np.testing.assert_allclose(norm.mean, seen.mean(0), rtol=1e-5)
    np.testing.assert_allclose(norm.m2 / (norm.count - 1), seen.var(0, ddof=1), rtol=1e-4)


@SHARED_STEP
def test_checkpoint_round_trip_and_damaged_checkpoints(tmp_path):
    config = shared_step_config()
    result = train(config, seed=0, progress=False)
    path = checkpoints.save(tmp_path / "agent.msgpack", result, {"note": "test"})
    loaded_config, params, norm, meta = checkpoints.load(path)
    assert loaded_config == config and meta["provenance"] == {"note": "test"}
    args = (SPEC, config.network)
    before = population_returns(*args, result.params.actor, result.normalizer, 4, 1, EPISODE)
    after = population_returns(*args, params.actor, norm, 4, 1, EPISODE)
    np.testing.assert_allclose(before, after, rtol=1e-6)

    good, sidecar = path.read_bytes(), path.with_suffix(".json")
    flipped = bytearray(good)
    flipped[len(good) // 2] ^= 0x01
    path.write_bytes(bytes(flipped))
    with pytest.raises(ValueError, match=f"{path}.*SHA-256"):
        checkpoints.load(path)
    path.write_bytes(good[: len(good) // 2])
    with pytest.raises(ValueError, match=f"{path}.*SHA-256"):
        checkpoints.load(path)
    path.write_bytes(good)
    meta = json.loads(sidecar.read_text())
    meta["config"]["network"]["cell_types"] = 8  # the parameters hold 16 types
    sidecar.write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=f"{sidecar} does not match the SHA-256 it records"):
        checkpoints.load(path)
    meta[checkpoints.SIDECAR_HASH] = checkpoints.sidecar_hash(meta)  # edited with care
    sidecar.write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=f"{path} does not hold the parameters"):
        checkpoints.load(path)


@pytest.mark.parametrize("cell_types", [None, 4])
def test_ppo_stops_when_training_diverges(cell_types):
    config = reach_config(cell_types, learning_rate=1e30, total_steps=2048, num_evals=1)
    with pytest.raises(TrainingDiverged, match=r"at step \d+"):
        train(config, seed=0, progress=False)


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="num_minibatches"):
        reach_config(num_envs=30)
    with pytest.raises(ValueError, match="cell_types"):
        NetworkConfig(hidden=(8,), cell_types=9)
    with pytest.raises(ValueError, match="registered"):
        train(reach_config(env=EnvSpec("no_such_env")), progress=False)


def test_shared_kernels_run_on_flattened_rows_bit_for_bit_as_the_plain_product():
    """``forward`` runs a shared kernel on the inputs' rows, flattened to 2-D, so that the
    kernel's gradient is a plain 2-D product (XLA on CPU took 2.3 times as long on the
    3-D one); at a PPO minibatch's shape (1024 sequences x 5 steps) the outputs and every
    gradient equal those of the plain product on the 3-D inputs, bit for bit."""
    keys = jax.random.split(jax.random.PRNGKey(0), 5)
    x = jax.random.normal(keys[0], (1024, 5, 27))
    shapes = [(27, 128), (128, 128), (128, 16)]
    layers = [
        (0.1 * jax.random.normal(k, shape), 0.1 * jax.random.normal(k, shape[1:]))
        for k, shape in zip(keys[1:4], shapes, strict=True)
    ]

    def plain(layers, x):
        for i, (kernel, bias) in enumerate(layers):
            x = x @ kernel + bias
            x = jax.nn.swish(x) if i < len(layers) - 1 else x
        return x

    def loss(run, layers, x):
        return jnp.sum(jnp.sin(run(layers, x)))

    ours, theirs = (jax.jit(run)(layers, x) for run in (forward, plain))
    np.testing.assert_array_equal(ours, theirs)
    grads = [
        jax.jit(jax.grad(loss, 1), static_argnums=0)(run, layers, x) for run in (forward, plain)
    ]
    for a, b in zip(*(jax.tree_util.tree_leaves(g) for g in grads), strict=True):
        np.testing.assert_array_equal(a, b)


def test_the_mean_network_runs_as_the_flax_layers_and_individuals_have_the_genomes_moments():
    """The pure forward pass of the mean phenotype is the Flax definition's at sigma ~ 0;
    the synapses of a type pair in 4,000 individuals have the pair's mean and spread; the
    noise of two layers is independent."""
    network = NetworkConfig(hidden=(32, 32), cell_types=4, rho_init=-2.0)
    actor = make_agent(network, 2, 1).actor
    params = actor.init(jax.random.PRNGKey(3), network)
    tables = genome.of_params(params)
    x = jax.random.normal(jax.random.PRNGKey(5), (7, 2))
    still = {name: g._replace(rho=jnp.full_like(g.rho, -30.0)) for name, g in tables.items()}
    flax_out = MLP(network, 2, 2).apply(
        genome.with_tables(params, still), x, rngs={"sample": jax.random.PRNGKey(0)}
    )
    np.testing.assert_allclose(forward(actor.layers(params, None), x), flax_out, atol=1e-5)
    keys = jax.random.split(jax.random.PRNGKey(6), 4000)
    noise = jax.vmap(actor.draw)(keys)
    w = np.asarray(actor.layers(params, noise)[1][0])[:, :8, :8]  # (type 0, type 0) block
    n, sigma = w.size, float(genome.sigma(tables["hidden_1"])[0, 0])
    assert abs(w.mean() - float(tables["hidden_1"].mu[0, 0])) < 4 * sigma / np.sqrt(n)
    assert abs(w.std() - sigma) < 4 * sigma / np.sqrt(2 * (n - 1))
    first, second = np.asarray(noise["hidden_0"][:, 0, 0]), np.asarray(noise["hidden_1"][:, 0, 0])
    assert abs(np.corrcoef(first, second)[0, 1]) < 4 / np.sqrt(len(keys))


@pytest.mark.parametrize("prior", ["mixture", "gaussian"])
def test_the_agents_kl_is_the_flax_layers_kl(prior):
    """The agent's genome KL at an individual's ``kl_key`` is what the SGB layers sow when
    applied with the individual's key, the mixture's Monte Carlo draws included."""
    network = NetworkConfig(
        hidden=(32, 16),
        cell_types=4,
        rho_init=-1.0,
        prior=prior,
        typed_inputs=True,
        sgb_output=True,
    )
    actor = make_agent(network, 3, 1).actor
    params = actor.init(jax.random.PRNGKey(0), network)
    assert list(actor.sgb_shapes) == ["hidden_0", "hidden_1", "out"]
    x = jnp.zeros((1, 3))

    def layers_kl(key):
        _, state = MLP(network, 2, 3).apply(params, x, rngs={"sample": key}, mutable=["losses"])
        return sum(genome.sown(state["losses"], "kl").values())

    many = jax.random.split(jax.random.PRNGKey(3), 200)
    ours = jax.jit(jax.vmap(lambda k: actor.kl(params, genome.kl_key(k))))(many)
    theirs = jax.jit(jax.vmap(layers_kl))(many)
    np.testing.assert_allclose(ours, theirs, rtol=1e-5)
    assert (prior == "gaussian") == bool(np.all(ours == ours[0]))


def test_the_authors_network_types_every_layer_and_draws_means_from_n_0_01():
    network = NetworkConfig(
        hidden=(64, 64),
        cell_types=64,
        typed_inputs=True,
        sgb_output=True,
        mean_init=0.1,
        rho_init=-7.0,
    )
    tables = genome.of_params(make_agent(network, 27, 8).actor.init(jax.random.PRNGKey(0), network))
    assert tables["hidden_0"].mu.shape == (27, 64)  # more types than inputs
    assert tables["out"].mu.shape == (64, 16)  # one type per output neuron
    np.testing.assert_allclose(np.asarray(tables["hidden_1"].mu).std(), 0.1, rtol=0.05)
    sigma = genome.sigma(tables["out"])
    np.testing.assert_allclose(sigma, np.log1p(np.exp(-7.0)), rtol=1e-6)
    small = replace(network, cell_types=16)
    tables = genome.of_params(make_agent(small, 27, 8).actor.init(jax.random.PRNGKey(0), small))
    assert tables["hidden_0"].mu.shape == (16, 16)  # 27 inputs in 16 types


def test_tanh_entropy_estimate_is_the_mean_negative_log_density():
    """E[tanh_gaussian_entropy] = E[-log p(tanh u)]; widening past the tanh range lowers it."""
    loc, u_noise = jnp.array([[0.3, -1.0]]), jax.random.normal(jax.random.PRNGKey(0), (200_000, 2))

    def both(scale):
        scale = jnp.full((1, 2), scale)
        u = loc + scale * u_noise
        return (
            float(jnp.mean(tanh_gaussian_entropy(scale, u))),
            float(jnp.mean(-tanh_gaussian_log_prob(u, loc, scale))),
        )

    estimate, reference = both(0.5)
    np.testing.assert_allclose(estimate, reference, atol=0.01)
    assert both(5.0)[0] < both(1.0)[0]


@SHARED_STEP
def test_killed_run_resumes_from_its_state_file_and_ends_as_an_uninterrupted_one(
    tmp_path, monkeypatch
):
    one_chunk = shared_step_config()
    config = replace(one_chunk, total_steps=3 * one_chunk.total_steps, num_evals=3)
    uninterrupted = train(config, seed=2, progress=False)
    state_file = tmp_path / "run.state.npz"
    trainer = make_trainer(config.step_settings())
    with killed_at_chunk(trainer, 2, monkeypatch), pytest.raises(KeyboardInterrupt):
        train(config, seed=2, progress=False, state_file=state_file)
    _drop_the_spreads(state_file)  # as a state saved before runs recorded them
    resumed = train(config, seed=2, progress=False, state_file=state_file)
    assert resumed.eval_steps == uninterrupted.eval_steps
    np.testing.assert_array_equal(resumed.eval_returns, uninterrupted.eval_returns)
    # every evaluation records the actor's spreads, the last those of the final actor; the
    # chunk saved without them has none
    assert resumed.eval_sigmas[0] is None
    assert resumed.eval_sigmas[1:] == uninterrupted.eval_sigmas[1:]
    assert len(resumed.eval_sigmas) == len(resumed.eval_steps)
    assert resumed.eval_sigmas[-1] == layer_sigmas(resumed.params.actor)
    assert set(resumed.eval_sigmas[-1]) == set(genome.of_params(resumed.params.actor)) != set()
    for a, b in zip(
        jax.tree_util.tree_leaves(resumed.params),
        jax.tree_util.tree_leaves(uninterrupted.params),
        strict=True,
    ):
        np.testing.assert_array_equal(a, b)
    # a finished state file returns the result at once; another run's is refused
    assert train(config, seed=2, progress=False, state_file=state_file).eval_returns == (
        resumed.eval_returns
    )
    with pytest.raises(ValueError, match="another run"):
        train(config, seed=3, progress=False, state_file=state_file)


def _drop_the_spreads(state_file) -> None:
    """Rewrite a training state's progress without its ``eval_sigmas``."""
    with np.load(state_file) as data:
        arrays = {name: data[name] for name in data.files}
    meta = json.loads(str(arrays["meta"]))
    del meta["progress"]["eval_sigmas"]
    arrays["meta"] = np.array(json.dumps(meta))
    with open(state_file, "wb") as out:
        np.savez(out, **arrays)


@SHARED_STEP
def test_a_sweep_reuses_a_finished_run_only_with_the_same_settings(tmp_path):
    from sgb.rl.runs import finished_run

    config = shared_step_config()
    result = train(config, seed=0, progress=False)
    checkpoint = checkpoints.save(tmp_path / "run.msgpack", result)
    assert finished_run(tmp_path / "missing.msgpack", config) is None
    kept = finished_run(checkpoint, config)
    assert kept["eval_returns"] == result.eval_returns
    assert kept["eval_steps"] == result.eval_steps
    assert finished_run(checkpoint, shared_step_config(eval_individuals=8)) is None
