"""Evolving a genome without gradients (chapter 6): an evolution strategy over the type
tables of an SGB classifier, scored by the innate accuracy of individuals developed from
each candidate genome.

Evolution sees fitness alone: the mean accuracy, on a batch of training examples, of
``individuals`` networks drawn from a candidate genome (``sgb.genome``). A deterministic
genome (sigma = 0) develops one network, its mean network, and evolution searches its
means only; a stochastic one develops ``individuals`` different networks, and evolution
searches the means and the spreads (rho) together. The strategy is OpenAI-ES (Salimans et
al. 2017, arXiv:1703.03864) as evosax implements it (``evosax.algorithms.Open_ES``:
antithetic perturbations, centred-rank fitness shaping, an optax optimiser on the mean);
its candidates are the genome's tables, flattened.
"""

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import optax

from sgb import genome, validation
from sgb.data import Dataset
from sgb.individuals import init_params
from sgb.layers import SGBMLP


@dataclasses.dataclass(frozen=True)
class EvolutionConfig:
    """One evolution: the classifier (one hidden layer of ``hidden`` neurons, ``cell_types``
    for input, hidden and output neurons; ``None`` one type per neuron), whether its
    development is ``stochastic``, and the strategy: ``candidates`` genomes per generation
    (even), each scored by ``individuals`` developed networks on ``batch_size`` training
    examples, for ``generations``; perturbations of SD ``es_sigma`` (table units), Adam at
    ``learning_rate`` on the mean genome. Means start as the layers initialise them, rho at
    ``rho_init``, below ``sgb.genome.SOFTPLUS_LIMIT``: above it the spread softplus(rho)
    saturates, fitness no longer changes with rho, and evolution could not bring it back."""

    hidden: int = 32
    cell_types: tuple[int | None, int, int | None] = (8, 8, None)
    stochastic: bool = True
    rho_init: float = -2.0
    candidates: int = 64
    individuals: int = 8
    generations: int = 300
    batch_size: int = 256
    es_sigma: float = 0.05
    learning_rate: float = 0.05
    eval_individuals: int = 100
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("hidden", "candidates", "individuals", "generations", "batch_size"):
            validation.integer(name, getattr(self, name))
        validation.integer("eval_individuals", self.eval_individuals)
        validation.instance("stochastic", self.stochastic, bool)
        if validation.real("rho_init", self.rho_init) >= genome.SOFTPLUS_LIMIT:
            raise ValueError(
                f"rho_init must be < {genome.SOFTPLUS_LIMIT}, where the spread saturates, "
                f"got {self.rho_init!r}"
            )
        if self.candidates % 2:
            raise ValueError(f"candidates must be even (antithetic pairs), got {self.candidates}")
        validation.positive("es_sigma", self.es_sigma)
        validation.positive("learning_rate", self.learning_rate)
        validation.seed("seed", self.seed)


def _model(config: EvolutionConfig, data: Dataset) -> SGBMLP:
    return SGBMLP(
        (config.hidden, data.num_classes),
        config.cell_types,
        rho_init=config.rho_init,
        in_features=data.x_train.shape[1],
    )


def _solution(tables: genome.Genome, stochastic: bool) -> dict:
    """What evolution searches: every layer's means, and its rho when ``stochastic``."""
    solution = {"mu": {name: layer.mu for name, layer in tables.items()}}
    if stochastic:
        solution["rho"] = {name: layer.rho for name, layer in tables.items()}
    return solution


def _tables(solution: dict, template: genome.Genome) -> genome.Genome:
    return {
        name: genome.LayerGenome(solution["mu"][name], solution.get("rho", {}).get(name, t.rho))
        for name, t in template.items()
    }


def accuracies(
    model: SGBMLP, params: dict, solution: dict, x: jnp.ndarray, y: jnp.ndarray, keys: jax.Array
) -> jnp.ndarray:
    """Accuracy on (x, y) of one network per key developed from ``solution`` (the mean
    network, once, for a solution without rho): shape (len(keys),) or (1,)."""
    developed = genome.with_tables(params, _tables(solution, genome.of_params(params)))
    if "rho" not in solution:
        logits = model.apply(developed, x, mean_network=True)[None]
    else:
        logits = jax.vmap(lambda k: model.apply(developed, x, rngs={"sample": k}))(keys)
    return (jnp.argmax(logits, -1) == y).mean(axis=-1)


def evolve(config: EvolutionConfig, data: Dataset) -> dict[str, Any]:
    """Evolve a genome on ``data`` and score its last mean genome on the test set.

    Returns per generation the candidates' mean and best fitness (training accuracy of
    their individuals, a fraction), and at the end the test accuracy of
    ``eval_individuals`` individuals of the mean genome (of its mean network, for a
    deterministic genome, all equal) and of its mean network, and its spreads' mean."""
    from evosax.algorithms import Open_ES  # here: importing evosax starts a JAX backend

    model = _model(config, data)
    key = jax.random.key(config.seed)
    init_key, key = jax.random.split(key)
    x_train, y_train = jnp.asarray(data.x_train), jnp.asarray(data.y_train)
    params = init_params(model, init_key, x_train[:1])
    start = _solution(genome.of_params(params), config.stochastic)
    strategy = Open_ES(
        population_size=config.candidates,
        solution=start,
        optimizer=optax.adam(config.learning_rate),
        std_schedule=optax.constant_schedule(config.es_sigma),
    )
    es_params = strategy.default_params
    key, es_key = jax.random.split(key)
    state = strategy.init(es_key, start, es_params)

    def generation(state, key):
        ask_key, batch_key, develop_key, tell_key = jax.random.split(key, 4)
        candidates, state = strategy.ask(ask_key, state, es_params)
        batch = jax.random.choice(batch_key, x_train.shape[0], (config.batch_size,))
        develop = jax.random.split(develop_key, (config.candidates, config.individuals))
        fitness = jax.vmap(
            lambda solution, keys: accuracies(
                model, params, solution, x_train[batch], y_train[batch], keys
            ).mean()
        )(candidates, develop)
        state, _ = strategy.tell(tell_key, candidates, -fitness, state, es_params)
        return state, (fitness.mean(), fitness.max())

    run = jax.jit(lambda state, keys: jax.lax.scan(generation, state, keys))
    state, (mean_fitness, best_fitness) = run(state, jax.random.split(key, config.generations))
    final = strategy.get_mean(state)
    x_test, y_test = jnp.asarray(data.x_test), jnp.asarray(data.y_test)
    eval_keys = jax.random.split(jax.random.key(config.seed + 1), config.eval_individuals)
    individuals = accuracies(model, params, final, x_test, y_test, eval_keys)
    mean_network = accuracies(model, params, {"mu": final["mu"]}, x_test, y_test, eval_keys)
    spreads = [genome.softplus(r).mean() for r in final.get("rho", {}).values()]
    return {
        "mean_fitness": np.asarray(mean_fitness).tolist(),
        "best_fitness": np.asarray(best_fitness).tolist(),
        "individuals": np.broadcast_to(individuals, (config.eval_individuals,)).tolist(),
        "mean_network": float(mean_network[0]),
        "sigma_mean": float(np.mean(spreads)) if spreads else 0.0,
    }
