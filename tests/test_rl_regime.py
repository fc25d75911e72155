"""The authors' training regime: one draw per step shared by every environment, and with
no spread at all, vanilla PPO; and the five places where their RL code departs from ours
(``self-supervisor/genomic_bottleneck_v2`` at 7effad6), each against their formula: the
aliased type pairs, the entropy's draw, the normaliser, the initialisation and the
evaluation."""

import json
from dataclasses import replace

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from interrupt import killed_at_chunk
from reach import SPEC, reach_config

from sgb import genome
from sgb.celltypes import assign_cell_types, expand_table
from sgb.experiments import regime_gait
from sgb.rl.agent import Network, NetworkConfig, Params, tanh_gaussian_log_prob
from sgb.rl.losses import entropy_estimate
from sgb.rl.normalizer import init_normalizer, normalize, update
from sgb.rl.ppo import PPOConfig, init_state, initial_params, state_agent, train
from sgb.rl.regimes import authors_regime, with_settings
from sgb.rl.trainer import make_trainer


def _assert_same_params(a, b) -> None:
    """Two parameter trees equal leaf by leaf, bit for bit."""
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
        np.testing.assert_array_equal(x, y)


def _authors(network: NetworkConfig, **kwargs):
    settings = dict(
        env=SPEC,
        network=network,
        regime="authors",
        num_envs=4,
        unroll_length=5,
        unrolls_per_iteration=2,
        num_minibatches=2,
        num_epochs=1,
        total_steps=2 * 4 * 5 * 2,
        kl_coef=0.0,
    )
    return reach_config(**{**settings, **kwargs})


def test_each_step_draws_one_actor_that_every_environment_shares():
    network = NetworkConfig(hidden=(8,), cell_types=4, bayesian_biases=True, rho_init=0.0)
    config = _authors(network)
    trainer = make_trainer(config.step_settings())
    ts = init_state(config, seed=0)
    # every environment in the same state: a shared actor acts alike in all of them
    same = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x[:1], x.shape), ts.env_state)
    used = []

    def recording(actor_params, individual, key):
        layers = type(trainer).acting_actor(trainer, actor_params, individual, key)
        used.append(layers)
        return layers

    object.__setattr__(trainer, "acting_actor", recording)
    try:
        step = trainer.shared_step(ts.params, ts.normalizer, same)

        @jax.jit
        def two_steps(state, keys):
            used.clear()
            carry, first = step((state, jnp.zeros(4)), keys[0])
            _, second = step(carry, keys[1])
            return first, second, carry[0].obs, used[0], used[1]

        first, second, obs_1, actor_0, actor_1 = two_steps(same, jax.random.split(ts.key))
    finally:
        object.__delattr__(trainer, "acting_actor")
    # one kernel and one bias vector per layer: no environment axis
    assert all(k.ndim == 2 and b.ndim == 1 for k, b in actor_0 + actor_1)
    # consecutive steps act with different weights
    assert not np.allclose(actor_0[0][0], actor_1[0][0])
    # the recorded actors are the ones that acted: they give the actions' log-densities
    for (obs, u, log_prob, *_), actor in ((first, actor_0), (second, actor_1)):
        loc, scale = trainer.agent.policy(actor, ts.normalizer, obs)
        np.testing.assert_allclose(log_prob, tanh_gaussian_log_prob(u, loc, scale), rtol=1e-5)
    loc_0, _ = trainer.agent.policy(actor_0, ts.normalizer, first[0])
    assert np.allclose(loc_0, loc_0[:1])  # shared: alike in the four identical states
    np.testing.assert_array_equal(first[0], np.broadcast_to(first[0][:1], first[0].shape))
    assert obs_1.shape == (4, 2)


def test_with_no_spread_the_authors_sgb_trains_as_vanilla_ppo():
    # one type per neuron everywhere, biases drawn too: with sigma = softplus(-30), about
    # 1e-13, every draw is the means, and the genome is a vanilla network's weights
    sgb = NetworkConfig(
        hidden=(8, 8),
        cell_types=8,
        sgb_output=True,
        bayesian_biases=True,
        rho_init=-30.0,
        mean_init=0.3,
        prior="gaussian",
    )
    sgb_config = _authors(sgb)
    vanilla_config = _authors(NetworkConfig(hidden=(8, 8)))
    ts_sgb = init_state(sgb_config, seed=1)
    ts_vanilla = init_state(vanilla_config, seed=1)

    def as_vanilla(params: Params) -> Params:
        def network(p):
            tables = genome.of_params(p)
            kernels = {name: {"kernel": tables[name].mu} for name in p["params"]}
            biases = {name: {"bias": tables[f"{name}/bias"].mu[0]} for name in p["params"]}
            return {"params": {n: kernels[n] | biases[n] for n in p["params"]}}

        return Params(network(params.actor), network(params.critic))

    vanilla = make_trainer(vanilla_config.step_settings())
    params = as_vanilla(ts_sgb.params)
    ts_vanilla = ts_vanilla._replace(params=params, opt_state=vanilla.optimizer.init(params))
    sgb_trainer = make_trainer(sgb_config.step_settings())
    ts_sgb, metrics_sgb = sgb_trainer.iterations(ts_sgb, 2)
    ts_vanilla, metrics_vanilla = vanilla.iterations(ts_vanilla, 2)
    trained = as_vanilla(ts_sgb.params)
    jax.tree_util.tree_map(
        lambda a, b: np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-6),
        trained,
        ts_vanilla.params,
    )
    for part in ("policy", "value", "entropy"):
        np.testing.assert_allclose(metrics_sgb[part], metrics_vanilla[part], rtol=1e-4)
    # and it moved: the comparison is between trained networks
    start = params.actor["params"]["out"]["kernel"]
    assert not np.allclose(start, trained.actor["params"]["out"]["kernel"])


def _their_flat_index(n_in: int, k_in: int, n_out: int, k_out: int) -> np.ndarray:
    """The flat table index of every synapse (n_in, n_out) as ``RL/utils.py`` computes it:
    ``get_indices`` pairs each synapse's (pre, post) types, and ``to1d(x, y, z, num_inp,
    num_out) = z * num_inp * num_out + y * num_out + x`` is called with x = post, y = pre,
    z = 0 and, for the sizes, the type arrays plus one (``gather_dims[i][-1] + 1``)."""
    pre = assign_cell_types(n_in, k_in)[:, None] * np.ones((1, n_out), dtype=np.int64)
    post = assign_cell_types(n_out, k_out)[None, :] * np.ones((n_in, 1), dtype=np.int64)
    num_inp, num_out = pre + 1, post + 1
    return 0 * num_inp * num_out + pre * num_out + post


def test_the_aliased_layers_read_the_table_entry_their_code_indexes():
    # the Ant's actor at 64 types: 27 observation entries -> 128 -> 128 -> 16 outputs
    config = NetworkConfig(
        cell_types=64, typed_inputs=True, sgb_output=True, aliased_pairs=True, mean_init=0.1
    )
    actor = Network(config.architecture, 27, 16)
    params = actor.init(jax.random.PRNGKey(0), config)
    stored = genome.of_params(params)
    used = {}
    for (name, (n_in, n_out)), (kernel, _) in zip(
        actor.sgb_shapes.items(), actor.layers(params, None), strict=False
    ):
        k_in, k_out = stored[name].mu.shape
        flat = _their_flat_index(n_in, k_in, n_out, k_out)
        np.testing.assert_array_equal(kernel, np.asarray(stored[name].mu).reshape(-1)[flat])
        used[name] = (len(np.unique(flat)), k_in * k_out)
    # the entries their layers use at 64 types, as counted by running their code
    assert used == {"hidden_0": (732, 1728), "hidden_1": (1263, 4096), "out": (474, 1024)}
    # the paper's layer (every pair its own Gaussian) reads entry [a, b] for pair (a, b)
    plain = Network(replace(config, aliased_pairs=False).architecture, 27, 16)
    kernel = plain.layers(params, None)[1][0]
    np.testing.assert_array_equal(kernel, expand_table(stored["hidden_1"].mu, (128, 128)))


def test_an_aliased_entry_learns_from_every_pair_that_reads_it():
    table = jnp.arange(12.0).reshape(3, 4)
    weights = jax.random.normal(jax.random.PRNGKey(1), (3, 4))
    grad = jax.grad(lambda t: jnp.sum(weights * genome.aliased_table(t)))(table)
    flat = _their_flat_index(3, 3, 4, 4)
    expected = np.zeros(12)
    np.add.at(expected, flat.reshape(-1), np.asarray(weights).reshape(-1))
    np.testing.assert_allclose(np.asarray(grad).reshape(-1), expected, rtol=1e-6)


def test_the_detached_entropy_trains_only_its_gaussian_part():
    # their dist_entropy: 0.5 + log(sqrt(2 pi) scale) + log|tanh'(u)| at u = torch.normal(
    # loc, scale), which passes no gradient: d/dloc = 0 and d/dscale = 1/scale
    loc = jnp.array([[0.3, -1.2], [2.0, 0.1]])
    scale = jnp.array([[0.5, 1.5], [0.2, 0.9]])
    key = jax.random.PRNGKey(3)

    def total(draw):
        return lambda loc, scale: jnp.sum(entropy_estimate(loc, scale, key, draw))

    d_loc, d_scale = jax.grad(total("detached"), argnums=(0, 1))(loc, scale)
    np.testing.assert_array_equal(d_loc, np.zeros_like(loc))
    np.testing.assert_allclose(d_scale, 1.0 / scale, rtol=1e-6)
    # the reparameterised draw trains the tanh term too; both estimate the same value
    r_loc, _ = jax.grad(total("reparameterised"), argnums=(0, 1))(loc, scale)
    assert np.all(np.abs(r_loc) > 1e-3)
    np.testing.assert_array_equal(
        total("detached")(loc, scale), total("reparameterised")(loc, scale)
    )


def _their_normaliser(batches: list[np.ndarray]) -> tuple[float, np.ndarray, np.ndarray]:
    """``update_normalization`` of ``RL/models.py``, line for line, over (T + 1, B, obs)
    batches: (num_steps, running_mean, running_variance)."""
    n, mean, var = 0.0, np.zeros(batches[0].shape[-1]), np.zeros(batches[0].shape[-1])
    for obs in batches:
        n += obs.shape[0] * obs.shape[1]
        to_old = obs - mean
        mean = mean + np.sum(to_old / n, axis=(0, 1))
        var = var + np.sum((obs - mean) * to_old, axis=(0, 1))
    return n, mean, var


def _their_normalize(n, mean, var, obs):
    variance = np.clip(var / (n + 1.0), 1e-6, 1e6)
    return np.clip((obs - mean) / np.sqrt(variance), -5, 5)


def test_the_authors_normaliser_is_theirs():
    rng = np.random.default_rng(0)
    obs = rng.normal(loc=[0.0, 3.0, -1.0], scale=[1.0, 0.01, 4.0], size=(4, 6, 8, 3))
    probe = rng.normal(loc=[0.0, 3.0, -1.0], scale=[1.0, 0.01, 4.0], size=(5, 3))
    obs, probe = obs.astype(np.float32), probe.astype(np.float32)
    # before any update: std 1e-3, so every input is clipped to +-5 (ours: unchanged)
    empty = init_normalizer(3)
    np.testing.assert_allclose(normalize(empty, probe, "authors"), np.clip(probe * 1e3, -5, 5))
    np.testing.assert_array_equal(normalize(empty, probe, "ours"), probe)
    ours = empty
    for i, batch in enumerate(obs):
        ours = update(ours, jnp.asarray(batch), jnp.ones(batch.shape[:-1]))
        n, mean, var = _their_normaliser(list(obs[: i + 1]))
        np.testing.assert_allclose(ours.count, n)
        np.testing.assert_allclose(ours.mean, mean, rtol=1e-5, atol=1e-6)
        np.testing.assert_allclose(ours.m2, var, rtol=1e-4)
        np.testing.assert_allclose(
            normalize(ours, probe, "authors"), _their_normalize(n, mean, var, probe), atol=1e-4
        )


def test_the_authors_normaliser_counts_each_unrolls_bootstrap_observation():
    network = NetworkConfig(hidden=(8,), normalizer="authors")
    config = _authors(network)
    trainer = make_trainer(config.step_settings())
    ts, _ = trainer.iterations(init_state(config, seed=0), 1)
    # 2 unrolls of 4 environments, 5 steps each and the bootstrap observation
    assert float(ts.normalizer.count) == 2 * 4 * (5 + 1)
    plain = _authors(NetworkConfig(hidden=(8,)))
    ts, _ = make_trainer(plain.step_settings()).iterations(init_state(plain, seed=0), 1)
    assert float(ts.normalizer.count) == 2 * 4 * 5


def test_the_authors_networks_start_as_torch_and_blitz_start_them():
    regime = authors_regime(PPOConfig())
    vanilla = make_trainer(regime.step_settings()).agent.init(
        jax.random.PRNGKey(0), jax.random.PRNGKey(1), regime.network
    )
    # torch's nn.Linear: kernel and bias uniform on +-1/sqrt(fan_in)
    for layer in vanilla.actor["params"].values():
        kernel, bias = np.asarray(layer["kernel"]), np.asarray(layer["bias"])
        bound = kernel.shape[0] ** -0.5
        for values in (kernel, bias):
            assert np.abs(values).max() <= bound
        assert abs(kernel.var() * 3 / bound**2 - 1) < 0.05  # Var U(-b, b) = b^2 / 3
        assert np.abs(bias).max() > bound / 2  # not zeros
    # their SGB genome: means and rho each N(init, 0.1^2), rho's around -7, biases too
    sgb = with_settings(
        replace(regime, network=replace(regime.network, cell_types=64, bayesian_biases=True)),
        "authors",
    )
    params = make_trainer(sgb.step_settings()).agent.init(
        jax.random.PRNGKey(0), jax.random.PRNGKey(1), sgb.network
    )
    tables = genome.of_params(params.actor)
    rho = np.concatenate([np.ravel(t.rho) for t in tables.values()])
    mu = np.concatenate([np.ravel(t.mu) for t in tables.values()])
    assert rho.size > 6000 and mu.size == rho.size
    assert abs(rho.mean() + 7.0) < 0.01 and abs(rho.std() - 0.1) < 0.005
    assert abs(mu.mean()) < 0.01 and abs(mu.std() - 0.1) < 0.005
    assert "hidden_0/bias" in tables


def test_the_authors_evaluate_at_step_0_and_after_every_chunk():
    config = replace(_authors(NetworkConfig(hidden=(8,))), num_evals=2, eval_at_start=True)
    result = train(config, seed=0, progress=False)
    steps = config.iterations // 2 * config.steps_per_iteration
    assert result.eval_steps == [0, steps, 2 * steps]
    assert np.all(np.isfinite(result.eval_returns))
    regime = authors_regime(PPOConfig())
    assert regime.eval_at_start and regime.eval_individuals == regime.num_envs == 2048


def test_an_authors_run_killed_mid_way_resumes_to_the_uninterrupted_run(tmp_path, monkeypatch):
    """Its state file keeps no environment state (every chunk resets them from the kept
    key), and the resumed run ends bit-identical to one never stopped; a state it keeps
    (``train``'s ``keep``) holds the agent of its chunk. The CPU time is kept with the
    state and added to on resuming; from a state saved before runs recorded it, the
    run's CPU time is unknown rather than short."""
    config = replace(
        _authors(NetworkConfig(hidden=(8,)), total_steps=3 * 2 * 4 * 5 * 2), num_evals=3
    )
    uninterrupted = train(config, seed=1, progress=False)
    trainer = make_trainer(config.step_settings())
    state_file = tmp_path / "run.state.npz"
    with killed_at_chunk(trainer, 2, monkeypatch), pytest.raises(KeyboardInterrupt):
        train(config, seed=1, progress=False, state_file=state_file)
    ts = init_state(config, 1)
    with np.load(state_file) as saved:
        kept = len(saved.files) - 1  # one entry is the meta
    env_leaves = len(jax.tree_util.tree_leaves((ts.env_state, ts.start_state)))
    assert kept == len(jax.tree_util.tree_leaves(ts)) - env_leaves
    with np.load(state_file) as saved:
        meta = json.loads(str(saved["meta"]))
        older = {name: saved[name] for name in saved.files}
    before = meta["progress"].pop("cpu_time_s")
    older_state = tmp_path / "older.state.npz"
    np.savez(older_state, **(older | {"meta": np.array(json.dumps(meta))}))
    kept = {1: tmp_path / "run.chunk1.npz", 3: tmp_path / "run.chunk3.npz"}
    resumed = train(config, seed=1, progress=False, state_file=state_file, keep=kept)
    assert resumed.cpu_time_s > before > 0
    from_older = train(config, seed=1, progress=False, state_file=older_state)
    assert from_older.cpu_time_s is None
    assert from_older.eval_returns == resumed.eval_returns == uninterrupted.eval_returns
    _assert_same_params(resumed.params, uninterrupted.params)
    # the states it keeps: chunk 1 was trained before the kill, so only chunk 3's is
    # written, and it is the agent the run ends with; keeping changes nothing trained
    assert not kept[1].exists()
    actor, normalizer = state_agent(kept[3], config, 1)
    _assert_same_params(Params(actor, uninterrupted.params.critic), uninterrupted.params)
    _assert_same_params(normalizer, uninterrupted.normalizer)
    with pytest.raises(ValueError, match="another run"):
        state_agent(kept[3], config, 2)


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_the_window_gait_plays_the_window_of_the_return_and_measures_its_velocity(
    direction, monkeypatch
):
    """On the same key the gait's return is the evaluation's, bit for bit; an actor pushed
    to act +-1 everywhere moves the reach point 0.1 a step each way, so its velocity is
    +-0.1 in every environment, its control cost 0.01 a step, and it walks where the
    walking speed is below that. The return is the episode's length times the reward per
    step over the episodes per environment (one here: Reach ends no episode early)."""
    config = _authors(NetworkConfig(hidden=(8,)))
    trainer = make_trainer(config.step_settings())
    params = initial_params(config, seed=0)
    out = params.actor["params"]["out"]
    loc_scale = jnp.array([20.0 * direction, 0.0])  # tanh(u) = +-1 whatever u's spread
    actor = {"params": {**params.actor["params"], "out": {**out, "bias": loc_scale}}}
    params = params._replace(actor=actor)
    normalizer = init_normalizer(2)
    key = jax.random.PRNGKey(3)
    ret, per_env = trainer.window_gait(params, normalizer, key, 4)
    assert ret == trainer.window_return(params, normalizer, key, 4)
    np.testing.assert_allclose(per_env["velocity"], 0.1 * direction * np.ones(4), rtol=1e-6)
    np.testing.assert_allclose(per_env["control_cost"], 0.01 * np.ones(4), rtol=1e-6)
    np.testing.assert_array_equal(per_env["episodes"], np.ones(4))
    monkeypatch.setattr(regime_gait, "WALKING_SPEED", 0.05)
    record = regime_gait.gait(config, params, normalizer, 4, seed=3)
    assert record["forward_velocity"] == pytest.approx(0.1 * direction, rel=1e-6)
    assert record["walks"] is (direction > 0)
    assert record["window_return"] == float(ret)
    made_of = config.episode_length * record["reward_per_step"] / record["episodes_per_env"]
    assert record["window_return"] == pytest.approx(made_of, rel=1e-5)


def test_smaller_intermediate_evaluations_leave_what_is_trained_bit_for_bit(monkeypatch):
    """Intermediate evaluations on 2 environments instead of all: the same parameters, bit for
    bit, and the same last evaluation; the evaluations before it play 2 environments."""
    config = replace(
        _authors(NetworkConfig(hidden=(8,)), total_steps=2 * 2 * 4 * 5 * 2),
        num_evals=2,
        eval_at_start=True,
    )
    everywhere = train(config, seed=2, progress=False)
    trainer = make_trainer(config.step_settings())
    real, sizes = trainer.window_return, []

    def counted(params, normalizer, key, n_envs):
        sizes.append(n_envs)
        return real(params, normalizer, key, n_envs)

    monkeypatch.setitem(trainer.__dict__, "window_return", counted)
    cheaper = replace(config, interim_eval_individuals=2)
    interim = train(cheaper, seed=2, progress=False)
    assert sizes == [2, 2, config.eval_individuals] and config.eval_individuals > 2
    assert interim.eval_returns[-1] == everywhere.eval_returns[-1]
    assert interim.eval_steps == everywhere.eval_steps
    _assert_same_params(interim.params, everywhere.params)
    assert cheaper.trains_as(config) and config.trains_as(cheaper)
    assert not cheaper.trains_as(replace(config, eval_individuals=2))
