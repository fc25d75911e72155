"""Evolving a genome without gradients (chapter 6): an evolution strategy over the type
means of an SGB classifier, scored by the innate accuracy of networks developed from each
candidate genome.

Evolution sees fitness alone: the mean accuracy of ``individuals`` networks developed from
a candidate genome (``sgb.genome``), each on its own batch of training examples. The
spread of every type pair is held at ``sigma``: a genome with sigma = 0 develops one
network, its mean network, scored on as many batches, so that both kinds of genome get
the same number of fitness evaluations and evolution searches the same means. The
strategy is OpenAI-ES (Salimans et al. 2017, arXiv:1703.03864) as evosax implements it
(``evosax.algorithms.Open_ES``: antithetic perturbations, centred-rank fitness shaping,
an optax optimiser on the mean); its candidates are the genome's means, flattened.
"""

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import optax

from sgb import genome, reliability, validation
from sgb.data import Dataset
from sgb.individuals import init_params
from sgb.layers import SGBMLP

TEST_PARTS = 10  # the test set in parts: per individual, 10 accuracies for the variance split


@dataclasses.dataclass(frozen=True)
class EvolutionConfig:
    """One evolution: the classifier (one hidden layer of ``hidden`` neurons, ``cell_types``
    for input, hidden and output neurons; ``None`` one type per neuron), the spread
    ``sigma`` of every type pair's weights (0: one network), and the strategy:
    ``candidates`` genomes per generation (even), each scored by ``individuals`` developed
    networks on a batch of ``batch_size`` training examples each, for ``generations``;
    perturbations of SD ``es_sigma`` (table units), Adam at ``learning_rate`` on the mean
    genome. Means start as the layers initialise them. The mean genome is scored on the
    test set after each of ``scorings`` equal spans of the generations (1: at the end)."""

    hidden: int = 32
    cell_types: tuple[int | None, int, int | None] = (8, 8, None)
    sigma: float = 0.0
    candidates: int = 64
    individuals: int = 8
    generations: int = 300
    batch_size: int = 256
    es_sigma: float = 0.05
    learning_rate: float = 0.05
    eval_individuals: int = 100
    seed: int = 0
    scorings: int = 1

    def __post_init__(self) -> None:
        for name in ("hidden", "candidates", "individuals", "generations", "batch_size"):
            validation.integer(name, getattr(self, name))
        validation.integer("eval_individuals", self.eval_individuals, minimum=2)
        validation.integer("scorings", self.scorings)
        if self.generations % self.scorings:
            raise ValueError(
                f"scorings ({self.scorings}) must divide generations ({self.generations})"
            )
        validation.non_negative("sigma", self.sigma)
        if self.candidates % 2:
            raise ValueError(f"candidates must be even (antithetic pairs), got {self.candidates}")
        validation.positive("es_sigma", self.es_sigma)
        validation.positive("learning_rate", self.learning_rate)
        validation.seed("seed", self.seed)

    @property
    def stochastic(self) -> bool:
        return self.sigma > 0


def _model(config: EvolutionConfig, data: Dataset) -> SGBMLP:
    return SGBMLP(
        (config.hidden, data.num_classes), config.cell_types, in_features=data.x_train.shape[1]
    )


def develop(params: dict, mu: dict, sigma: float) -> dict:
    """``params`` with every SGB layer's means ``mu`` (path -> table) and every spread at
    ``sigma`` (rho = log(expm1(sigma)); for 0, a rho whose draws the mean network ignores)."""
    rho = float(np.log(np.expm1(sigma))) if sigma > 0 else -30.0
    tables = {
        name: genome.LayerGenome(mu[name], jnp.full_like(layer.rho, rho))
        for name, layer in genome.of_params(params).items()
    }
    return genome.with_tables(params, tables)


def accuracies(
    model: SGBMLP,
    developed: dict,
    x: jnp.ndarray,
    y: jnp.ndarray,
    keys: jax.Array,
    stochastic: bool,
) -> jnp.ndarray:
    """Accuracy of network j on (x[j], y[j]), x (K, B, features), y (K, B): network j drawn
    with ``keys[j]``, or for a genome that is not ``stochastic`` its mean network on every
    batch; shape (K,)."""
    return _correct(model, developed, x, y, keys, stochastic).mean(axis=-1)


def _correct(model, developed, x, y, keys, stochastic) -> jnp.ndarray:
    """Whether network j (``accuracies``) names each example of x[j] right, (K, B)."""
    if not stochastic:
        logits = jax.vmap(lambda xj: model.apply(developed, xj, mean_network=True))(x)
    else:
        logits = jax.vmap(lambda k, xj: model.apply(developed, xj, rngs={"sample": k}))(keys, x)
    return jnp.argmax(logits, -1) == y


def part_accuracies(
    model: SGBMLP,
    developed: dict,
    x: jnp.ndarray,
    y: jnp.ndarray,
    keys: jax.Array,
    stochastic: bool,
) -> np.ndarray:
    """Each network's accuracy on each of ``TEST_PARTS`` equal parts of (x, y), x (N,
    features), the remainder left out: shape (len(keys), TEST_PARTS); one row for a
    genome that is not ``stochastic``."""
    size = len(x) // TEST_PARTS
    x, y = x[: size * TEST_PARTS], y[: size * TEST_PARTS]
    n = len(keys) if stochastic else 1
    every = (n, *x.shape)
    correct = _correct(model, developed, jnp.broadcast_to(x, every), y, keys[:n], stochastic)
    return np.asarray(correct, dtype=np.float64).reshape(n, TEST_PARTS, size).mean(axis=-1)


def evolve(config: EvolutionConfig, data: Dataset) -> dict[str, Any]:
    """Evolve a genome's means on ``data`` and score its mean genome on the test set.

    Returns per generation the candidates' mean and best fitness (training accuracy of
    their networks, a fraction); at the end the test accuracy of ``eval_individuals``
    individuals of the mean genome (all equal for sigma = 0) and of its mean network, and
    the split of the individuals' accuracies over ``TEST_PARTS`` parts of the test set
    into variance between individuals and residual, the parts' shared difficulty taken
    out (``sgb.reliability.variance_split``, crossed; none where every individual scores
    alike, as at sigma = 0); and ``course``: after each of ``config.scorings`` equal spans
    of the generations, the same scores (``score``) with the individuals' mean
    (``accuracy``) in place of each one's, the last the end's.
    The generations run as one sequence of keys however they are cut into spans."""
    from evosax.algorithms import Open_ES  # here: importing evosax starts a JAX backend

    model = _model(config, data)
    key = jax.random.key(config.seed)
    init_key, key = jax.random.split(key)
    x_train, y_train = jnp.asarray(data.x_train), jnp.asarray(data.y_train)
    params = init_params(model, init_key, x_train[:1])
    start = {name: layer.mu for name, layer in genome.of_params(params).items()}
    strategy = Open_ES(
        population_size=config.candidates,
        solution=start,
        optimizer=optax.adam(config.learning_rate),
        std_schedule=optax.constant_schedule(config.es_sigma),
    )
    es_params = strategy.default_params
    key, es_key = jax.random.split(key)
    state = strategy.init(es_key, start, es_params)
    shape = (config.candidates, config.individuals)

    def generation(state, key):
        ask_key, batch_key, develop_key, tell_key = jax.random.split(key, 4)
        candidates, state = strategy.ask(ask_key, state, es_params)
        batches = jax.random.choice(batch_key, x_train.shape[0], (*shape, config.batch_size))
        develop_keys = jax.random.split(develop_key, shape)
        fitness = jax.vmap(
            lambda mu, batch, keys: accuracies(
                model,
                develop(params, mu, config.sigma),
                x_train[batch],
                y_train[batch],
                keys,
                config.stochastic,
            ).mean()
        )(candidates, batches, develop_keys)
        state, _ = strategy.tell(tell_key, candidates, -fitness, state, es_params)
        return state, (fitness.mean(), fitness.max())

    run = jax.jit(lambda state, keys: jax.lax.scan(generation, state, keys))
    spans = jax.random.split(key, config.generations).reshape(config.scorings, -1)
    mean_fitness, best_fitness, course = [], [], []
    for j, keys in enumerate(spans):
        state, (mean_j, best_j) = run(state, keys)
        mean_fitness += np.asarray(mean_j).tolist()
        best_fitness += np.asarray(best_j).tolist()
        scored = score(model, develop(params, strategy.get_mean(state), config.sigma), config, data)
        course.append(
            {
                "generation": (j + 1) * len(keys),
                "accuracy": float(np.mean(scored["individuals"])),
                **{k: v for k, v in scored.items() if k != "individuals"},
            }
        )
    return {"mean_fitness": mean_fitness, "best_fitness": best_fitness, **scored, "course": course}


def score(model: SGBMLP, developed: dict, config: EvolutionConfig, data: Dataset) -> dict:
    """The test accuracy of ``config.eval_individuals`` individuals of the developed mean
    genome (``individuals``, all equal for sigma = 0), of its mean network
    (``mean_network``), and, where the individuals differ at all, the crossed variance
    split of their accuracies over ``TEST_PARTS`` parts of the test set
    (``variance_split``: SDs in accuracy units, ICC, the F-test's p)."""
    x_test, y_test = jnp.asarray(data.x_test), jnp.asarray(data.y_test)
    eval_keys = jax.random.split(jax.random.key(config.seed + 1), config.eval_individuals)
    parts = part_accuracies(model, developed, x_test, y_test, eval_keys, config.stochastic)
    mean_network = part_accuracies(model, developed, x_test, y_test, eval_keys, False)
    out = {
        "individuals": np.broadcast_to(parts.mean(axis=1), (config.eval_individuals,)).tolist(),
        "mean_network": float(mean_network.mean()),
    }
    if config.stochastic and np.ptp(parts.mean(axis=1)) > 0:  # else every one is alike
        split = reliability.variance_split(parts, crossed=True)
        out["variance_split"] = {
            "between_sd": float(np.sqrt(split.between_var)),
            "within_sd": float(np.sqrt(split.within_var)),
            "icc": split.icc,
            "p": split.p,
        }
    return out
