"""The authors' training regime: one draw per step shared by every environment, and with
no spread at all, vanilla PPO."""

import jax
import jax.numpy as jnp
import numpy as np
from reach import SPEC, reach_config

from sgb import genome
from sgb.rl.agent import NetworkConfig, Params, tanh_gaussian_log_prob
from sgb.rl.ppo import init_state
from sgb.rl.trainer import make_trainer


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
