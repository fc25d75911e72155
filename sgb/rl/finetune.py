"""A developed network as the start of further learning: the plain (vanilla) actor whose
weights are those of one individual of a genome, or of its mean network.

An SGB actor develops into a phenotype, the (kernel, bias) of every layer
(``sgb.rl.agent.Network.layers``); a vanilla actor of the same widths holds exactly
those arrays as its parameters, and its forward pass is the same function
(``sgb.rl.agent.forward``), so it plays as the individual does (to float rounding: an
individual's kernels run there as a batch of one, here as plain matrices; the mean
network's run as plain matrices in both, so it plays exactly alike). Training it
(``sgb.rl.ppo.train`` with ``initial=sgb.rl.ppo.Start(actor, normalizer)``) changes
every weight on its own: the genome's type structure is not kept.
"""

import jax

from sgb import validation
from sgb.rl.agent import NetworkConfig
from sgb.rl.population import check_actor_params
from sgb.rl.ppo import PPOConfig
from sgb.rl.trainer import make_trainer


def plain_network(network: NetworkConfig) -> NetworkConfig:
    """The vanilla network of ``network``'s hidden widths (default initialisation)."""
    validation.instance("network", network, NetworkConfig)
    return NetworkConfig(hidden=network.hidden)


def individual_key(seed: int, n_individuals: int, index: int) -> jax.Array:
    """The key ``sgb.rl.population.population_returns(..., n_individuals, seed=seed)``
    draws individual ``index`` with: ``split(split(PRNGKey(seed))[0], n_individuals)[index]``."""
    validation.integer("n_individuals", n_individuals)
    if not 0 <= validation.integer("index", index, minimum=0) < n_individuals:
        raise ValueError(f"index must lie in [0, {n_individuals}), got {index}")
    ind_key, _ = jax.random.split(jax.random.PRNGKey(validation.seed("seed", seed)))
    return jax.random.split(ind_key, n_individuals)[index]


def plain_actor(ppo: PPOConfig, actor_params: dict, key: jax.Array | None = None) -> dict:
    """The ``{"params": ...}`` of the vanilla actor (``plain_network(ppo.network)``) whose
    kernels (n_in, n_out) and biases (n_out,) are the phenotype of the individual born from
    ``key`` under the genome ``actor_params`` of a run of ``ppo`` (its environment and
    network); ``key=None``: of the mean network. A vanilla actor comes back as it is."""
    validation.instance("ppo", ppo, PPOConfig)
    check_actor_params(actor_params)
    actor = make_trainer(ppo.step_settings()).agent.actor
    noise = None if key is None else actor.draw(key)
    layers = actor.layers(actor_params, noise)
    return {
        "params": {
            name: {"kernel": kernel, "bias": bias}
            for name, (kernel, bias) in zip(actor.names, layers, strict=True)
        }
    }
