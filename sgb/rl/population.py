"""Innate returns of a population of individuals (and of the mean network) on an environment.

Every individual drawn from a trained genome plays ``episodes`` episodes on
an environment variant with no further learning. Its actions are
deterministic (tanh of the Gaussian mean), so the spread of its returns over
episodes comes only from the random initial state; with ``stochastic=True``
they are sampled from the policy, as in training (and in the authors' Figure 5).
All N x episodes rollouts run in one jitted, vmapped call.
"""

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from sgb import validation
from sgb.noise import standard_normal
from sgb.rl.agent import Architecture, NetworkConfig, make_agent
from sgb.rl.envs import EnvSpec, make_env
from sgb.rl.normalizer import Normalizer


@partial(jax.jit, static_argnames=("spec", "architecture", "episode_length"))
def episode_returns(
    spec: EnvSpec,
    architecture: Architecture,
    actor_params: dict,
    normalizer: Normalizer,
    ind_keys: jax.Array | None,
    reset_keys: jax.Array,
    episode_length: int,
    action_key: jax.Array | None,
) -> jnp.ndarray:
    """Returns (N, E) for reset keys (N, E, 2): row i played by individual ``ind_keys[i]``,
    or every row by the mean network when ``ind_keys`` is None. Actions are tanh of the
    Gaussian mean, or sampled with ``action_key`` when it is given."""
    env = make_env(spec)
    agent = make_agent(architecture, env.observation_size, env.action_size)
    noise = None if ind_keys is None else jax.vmap(agent.actor.draw)(ind_keys)
    layers = agent.actor.layers(actor_params, noise)
    state = jax.vmap(jax.vmap(env.reset))(reset_keys)

    def step(carry, t):
        state, total, alive = carry
        loc, scale = agent.policy(layers, normalizer, state.obs)
        if action_key is not None:
            loc = loc + scale * standard_normal(jax.random.fold_in(action_key, t), loc.shape)
        state = jax.vmap(jax.vmap(env.step))(state, jnp.tanh(loc))
        total = total + alive * state.reward
        alive = alive * (1.0 - state.done)
        return (state, total, alive), None

    zeros = jnp.zeros(reset_keys.shape[:2])
    carry = (state, zeros, zeros + 1.0)
    (_, total, _), _ = jax.lax.scan(step, carry, jnp.arange(episode_length))
    return total


def check_normalizer(normalizer: Normalizer, size: int) -> Normalizer:
    """``normalizer`` if it holds finite statistics of observations of ``size`` entries (a
    count >= 0, a mean and squared deviations >= 0 of shape (size,)); else a ``ValueError``
    (``TypeError`` for another type) naming what is wrong."""
    validation.instance("normalizer", normalizer, Normalizer)
    validation.finite_tree("normalizer", normalizer._asdict())
    count = validation.array("normalizer.count", normalizer.count, ndim=0)
    for name in ("mean", "m2"):
        field = validation.array(f"normalizer.{name}", getattr(normalizer, name), ndim=1)
        if field.shape != (size,):
            raise ValueError(
                f"normalizer.{name} must have shape ({size},) for observations of {size} "
                f"entries, got {tuple(field.shape)}"
            )
    if not validation.is_traced(count) and (
        float(count) < 0 or bool(np.any(np.asarray(normalizer.m2) < 0))
    ):
        raise ValueError("normalizer.count and normalizer.m2 must be >= 0")
    return normalizer


def check_actor_params(actor_params: dict) -> dict:
    """``actor_params`` if it is a ``{"params": ...}`` tree with finite leaves."""
    if not isinstance(actor_params, dict) or "params" not in actor_params:
        raise TypeError(f"actor_params must be a dict {{'params': ...}}, got {actor_params!r}")
    return validation.finite_tree("actor_params", actor_params)


def check_actor_shapes(actor_params: dict, network: NetworkConfig, spec: EnvSpec) -> dict:
    """``actor_params`` if its leaves have the shapes of the actor ``network`` describes on
    the environment of ``spec``; else a ``ValueError`` naming the first leaves that differ,
    (leaf, shape, expected shape)."""
    env = make_env(spec)
    actor = make_agent(network.architecture, env.observation_size, env.action_size).actor
    expected = jax.eval_shape(lambda: actor.init(jax.random.PRNGKey(0), network))
    diff = validation.shape_differences(actor_params, expected)
    if diff:
        raise ValueError(
            f"actor_params do not have the shapes of the actor that network describes on "
            f"{spec.name} (first differences, (leaf, shape, expected shape): {diff})"
        )
    return actor_params


def population_keys(n_individuals: int, episodes: int, seed: int) -> tuple[jax.Array, jax.Array]:
    """The keys of a population's evaluation from ``seed``: one per individual (N, 2) and
    one per episode's reset (N, E, 2)."""
    validation.integer("n_individuals", n_individuals)
    validation.integer("episodes", episodes)
    validation.seed("seed", seed)
    ind_key, env_key = jax.random.split(jax.random.PRNGKey(seed))
    reset_keys = jax.random.split(env_key, n_individuals * episodes)
    return jax.random.split(ind_key, n_individuals), reset_keys.reshape(n_individuals, episodes, -1)


def population_returns(
    spec: EnvSpec,
    network: NetworkConfig,
    actor_params: dict,
    normalizer: Normalizer,
    n_individuals: int,
    episodes: int,
    episode_length: int,
    seed: int = 0,
    mean_network: bool = False,
    stochastic: bool = False,
) -> np.ndarray:
    """Innate returns, shape (n_individuals, episodes), in one jitted, vmapped call.

    Individual i is drawn with key ``split(split(PRNGKey(seed))[0], N)[i]``;
    its episodes start from initial states drawn from the other half of the
    seed. The same ``seed`` gives the same individuals and initial states on
    every environment variant, so rows are comparable across variants. With
    ``mean_network=True`` the mean network plays the very same initial
    states, row by row (for paired comparisons). With ``stochastic=True`` actions are
    sampled from the policy (noise from ``fold_in(PRNGKey(seed), 1)``).

    The arguments are checked first: counts and ``seed`` integers, ``actor_params`` finite
    and of the shapes of ``network``'s actor, ``normalizer`` finite statistics of the
    environment's observations.
    """
    validation.instance("spec", spec, EnvSpec)
    validation.instance("network", network, NetworkConfig)
    validation.integer("episode_length", episode_length)
    validation.instance("mean_network", mean_network, bool)
    validation.instance("stochastic", stochastic, bool)
    check_actor_shapes(check_actor_params(actor_params), network, spec)
    check_normalizer(normalizer, make_env(spec).observation_size)
    ind_keys, reset_keys = population_keys(n_individuals, episodes, seed)
    total = episode_returns(
        spec,
        network.architecture,
        actor_params,
        normalizer,
        None if mean_network else ind_keys,
        reset_keys,
        episode_length,
        jax.random.fold_in(jax.random.PRNGKey(seed), 1) if stochastic else None,
    )
    return np.asarray(total)
