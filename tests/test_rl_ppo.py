"""PPO and populations on a cheap environment: learning, individuals, checkpoints, GAE."""

import json
from dataclasses import replace

import brax.envs
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from brax.envs.base import State
from reach import (
    EPISODE,
    SGB_TYPES,
    SHARED_STEP,
    SPEC,
    Reach,
    reach_config,
    shared_step_config,
)

from sgb import stats
from sgb.divergence import TrainingDiverged
from sgb.experiments.rl import PopulationConfig, authors_protocol
from sgb.population import init_params
from sgb.rl import checkpoints
from sgb.rl.envs import EnvSpec
from sgb.rl.networks import (
    MLP,
    NetworkConfig,
    action_distribution,
    draw_noise,
    forward,
    individuals,
    network_kl,
    sgb_layers,
    tanh_gaussian_entropy,
    tanh_gaussian_log_prob,
)
from sgb.rl.normalizer import init_normalizer, normalize, update
from sgb.rl.population import population_returns
from sgb.rl.ppo import _unroll, gae, init_state, train, train_iterations


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
    before = train_iterations._cache_size()
    train(config, seed=0, progress=False)
    assert train_iterations._cache_size() == before + 1
    # the initial spread, the length and the evaluations of a run do not enter the step
    wider = replace(network, rho_init=-1.0)
    train(replace(config, network=wider, total_steps=64, num_evals=2, eval_individuals=3), 0, False)
    assert train_iterations._cache_size() == before + 1


def _noise(model, params, keys):
    return jax.vmap(lambda k: draw_noise(model, params, k))(keys)


def _sgb_params(rho_init=-1.0):
    network = NetworkConfig(hidden=(32, 32), cell_types=4, rho_init=rho_init)
    config = reach_config(4, network=network)
    return config, init_state(config, seed=3)


def test_same_key_same_individual_and_return():
    config, ts = _sgb_params()
    actor = MLP(config.network, 2, 2)
    keys = jax.random.split(jax.random.PRNGKey(0), 2)
    a = individuals(actor, ts.params.actor, _noise(actor, ts.params.actor, keys))
    b = individuals(actor, ts.params.actor, _noise(actor, ts.params.actor, keys))
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
    expected = stats.one_sample_t(out["individuals"].mean(axis=1), out["mean_network"].mean())
    assert out["t"] == expected.statistic and out["dof"] == 11


def test_ratio_is_one_for_the_collecting_individual():
    """Rebuilding each unroll's individual from its kept noise reproduces the behaviour policy."""
    config, ts = _sgb_params()
    ts, data = _unroll(ts, config)
    actor = MLP(config.network, 2, 2)
    layers = individuals(actor, ts.params.actor, data.actor_noise)
    loc, scale = action_distribution(forward(layers, normalize(ts.normalizer, data.obs)))
    np.testing.assert_allclose(tanh_gaussian_log_prob(data.u, loc, scale), data.log_prob, atol=1e-4)


def test_gae_matches_a_loop():
    rng = np.random.default_rng(0)
    t = 6
    reward, value = rng.normal(size=(2, t))
    next_value = np.append(value[1:], rng.normal())  # V(s_{t+1}), as the unroll gives it
    done = np.array([0, 0, 1, 0, 0, 1.0])
    trunc = np.array([0, 0, 0, 0, 0, 1.0])
    adv, target = gae(*(jnp.asarray(x) for x in (reward, value, next_value, done, trunc)), 0.9, 0.8)
    lambda_return, policy_adv = np.zeros(t), np.zeros(t)
    for i in reversed(range(t)):
        terminal = done[i] * (1 - trunc[i])
        bootstrap = next_value[i] if i == t - 1 or done[i] else lambda_return[i + 1]
        policy_adv[i] = reward[i] + 0.9 * (1 - terminal) * bootstrap - value[i]
        # G_t = r_t + gamma * ((1 - lambda) V(s_{t+1}) + lambda G_{t+1}), cut at episode ends
        following = next_value[i] if i == t - 1 or done[i] else lambda_return[i + 1]
        mixed = (1 - 0.8) * next_value[i] + 0.8 * following
        lambda_return[i] = reward[i] + 0.9 * (1 - terminal) * mixed
    np.testing.assert_allclose(target, lambda_return, rtol=1e-5)
    np.testing.assert_allclose(adv, policy_adv, rtol=1e-5)


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


def test_phenotype_agrees_with_the_sgb_layers():
    """The mean network equals SGBDense's; sampled weights have each type pair's mean and std."""
    config, ts = _sgb_params(rho_init=-2.0)
    actor = MLP(config.network, 2, 2)
    x = jax.random.normal(jax.random.PRNGKey(5), (7, 2))
    layers = individuals(actor, ts.params.actor, None)
    expected = actor.apply(ts.params.actor, x, mean_network=True)
    np.testing.assert_allclose(forward(layers, x), expected, rtol=1e-5, atol=1e-6)
    keys = jax.random.split(jax.random.PRNGKey(6), 4000)
    layers = individuals(actor, ts.params.actor, _noise(actor, ts.params.actor, keys))
    genome = ts.params.actor["params"]["hidden_1"]["genome"]
    w = np.asarray(layers[1][0])[:, :8, :8]  # the (type 0, type 0) block of the 32x32 layer
    np.testing.assert_allclose(w.mean(), genome["mu"][0, 0], atol=3e-3)
    np.testing.assert_allclose(w.std(), jax.nn.softplus(genome["rho"][0, 0]), rtol=2e-2)


@pytest.mark.parametrize(
    ("prior", "typed_sgb_out"), [("mixture", False), ("gaussian", False), ("gaussian", True)]
)
def test_rl_and_layer_paths_draw_the_same_individual(prior, typed_sgb_out):
    """From the same key, the RL phenotype has the SGB layers' kernels and outputs; the
    network's KL is the layers' (exactly for the Gaussian prior, on average over keys
    for the mixture, whose per-pair draws come from other keys)."""
    network = NetworkConfig(
        hidden=(32, 16),
        cell_types=4,
        rho_init=-1.0,
        prior=prior,
        typed_inputs=typed_sgb_out,
        sgb_output=typed_sgb_out,
    )
    actor = MLP(network, 2, 3)
    params = init_params(actor, jax.random.PRNGKey(0), jnp.zeros((1, 3)))
    keys = jax.random.split(jax.random.PRNGKey(1), 3)
    layers = individuals(actor, params, _noise(actor, params, keys))
    names = list(sgb_layers(actor))
    assert names == ["hidden_0", "hidden_1"] + ["out"] * typed_sgb_out
    x = jax.random.normal(jax.random.PRNGKey(2), (5, 3))
    for i, key in enumerate(keys):
        out, state = actor.apply(params, x, rngs={"sample": key}, mutable=["individual", "losses"])
        for j, name in enumerate(names):
            kernel = state["individual"][name]["genome"]["kernel"]
            np.testing.assert_allclose(layers[j][0][i], kernel, rtol=1e-6, atol=1e-7)
        np.testing.assert_allclose(
            forward([(k[i] if k.ndim == 3 else k, b) for k, b in layers], x),
            out,
            rtol=1e-5,
            atol=1e-6,
        )

    def layers_kl(key):
        _, state = actor.apply(params, x, rngs={"sample": key}, mutable=["losses"])
        return sum(state["losses"][name]["genome"]["kl"] for name in names)

    many = jax.random.split(jax.random.PRNGKey(3), 2000)
    ours = jax.vmap(lambda k: network_kl(actor, params, k))(many)
    theirs = jax.vmap(layers_kl)(many)
    if prior == "gaussian":
        np.testing.assert_allclose(ours, theirs, rtol=1e-5)
    else:
        se = np.hypot(ours.std(), theirs.std()) / np.sqrt(len(many))
        assert abs(float(ours.mean() - theirs.mean())) < 4 * se


def test_the_authors_network_types_every_layer_and_draws_means_from_n_0_01():
    network = NetworkConfig(
        hidden=(64, 64),
        cell_types=64,
        typed_inputs=True,
        sgb_output=True,
        mean_init=0.1,
        rho_init=-7.0,
    )
    params = init_params(MLP(network, 16, 27), jax.random.PRNGKey(0), jnp.zeros((1, 27)))["params"]
    assert params["hidden_0"]["genome"]["mu"].shape == (27, 64)  # more types than inputs
    assert params["out"]["genome"]["mu"].shape == (64, 16)  # one type per output neuron
    mu = np.asarray(params["hidden_1"]["genome"]["mu"])
    np.testing.assert_allclose(mu.std(), 0.1, rtol=0.05)
    sigma = jax.nn.softplus(params["out"]["genome"]["rho"])
    np.testing.assert_allclose(sigma, np.log1p(np.exp(-7.0)), rtol=1e-6)
    small = replace(network, cell_types=16)
    params = init_params(MLP(small, 16, 27), jax.random.PRNGKey(0), jnp.zeros((1, 27)))["params"]
    assert params["hidden_0"]["genome"]["mu"].shape == (16, 16)  # 27 inputs in 16 types


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
    from sgb.rl import ppo

    one_chunk = shared_step_config()
    config = replace(one_chunk, total_steps=3 * one_chunk.total_steps, num_evals=3)
    uninterrupted = train(config, seed=2, progress=False)
    state_file = tmp_path / "run.state.npz"
    real, calls = ppo.train_iterations, []

    def killed_at_the_second_chunk(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(ppo, "train_iterations", killed_at_the_second_chunk)
    with pytest.raises(KeyboardInterrupt):
        train(config, seed=2, progress=False, state_file=state_file)
    monkeypatch.setattr(ppo, "train_iterations", real)
    resumed = train(config, seed=2, progress=False, state_file=state_file)
    assert resumed.eval_steps == uninterrupted.eval_steps
    np.testing.assert_array_equal(resumed.eval_returns, uninterrupted.eval_returns)
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


@SHARED_STEP
def test_a_sweep_reuses_a_finished_run_only_with_the_same_settings(tmp_path):
    from sgb.experiments.rl import finished_run

    config = shared_step_config()
    result = train(config, seed=0, progress=False)
    checkpoint = checkpoints.save(tmp_path / "run.msgpack", result)
    assert finished_run(tmp_path / "missing.msgpack", config) is None
    kept = finished_run(checkpoint, config)
    assert kept["eval_returns"] == result.eval_returns
    assert kept["eval_steps"] == result.eval_steps
    assert finished_run(checkpoint, shared_step_config(eval_individuals=8)) is None
