"""Training SGB classifiers with the ELBO, and their innate (zero-shot) evaluation."""

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax.training.train_state import TrainState
from tqdm.auto import tqdm

from sgb.data import Dataset
from sgb.elbo import elbo_loss
from sgb.layers import SGBMLP, KLCounting
from sgb.population import apply_mean_network, apply_population, init_params
from sgb.priors import GaussianPrior, Prior


@dataclasses.dataclass(frozen=True)
class ClassifierConfig:
    """An SGB MLP classifier and its training.

    ``hidden``: hidden widths; ``cell_types``: types of the input, each hidden
    layer and the output (``None`` = one type per neuron, a plain BNN layer).
    ``kl_scale`` multiplies the per-example KL weight 1/n_train.
    """

    hidden: tuple[int, ...] = (64,)
    cell_types: tuple[int | None, ...] = (None, None, None)
    prior: Prior = GaussianPrior(0.1)
    kl_counting: KLCounting = "synapse"
    kl_scale: float = 1.0
    rho_init: float = -5.0
    num_samples: int = 2
    learning_rate: float = 1e-3
    batch_size: int = 64
    epochs: int = 20
    eval_individuals: int = 10
    seed: int = 0


def make_model(config: ClassifierConfig, num_classes: int) -> SGBMLP:
    """The SGB MLP a config describes."""
    return SGBMLP(
        widths=(*config.hidden, num_classes),
        cell_types=config.cell_types,
        prior=config.prior,
        kl_counting=config.kl_counting,
        rho_init=config.rho_init,
    )


def _make_train_step(model: SGBMLP, config: ClassifierConfig, n_train: int):
    kl_weight = config.kl_scale / n_train

    @jax.jit
    def train_step(state: TrainState, x, y, key):
        def loss_fn(params):
            return elbo_loss(
                model, params, x, y, key, num_samples=config.num_samples, kl_weight=kl_weight
            )

        (loss, parts), grads = jax.value_and_grad(loss_fn, has_aux=True)(state.params)
        return state.apply_gradients(grads=grads), {"loss": loss, **parts}

    return train_step


def train_classifier(
    config: ClassifierConfig, data: Dataset, progress: bool = True
) -> tuple[SGBMLP, Any, list[dict[str, float]]]:
    """Train with Adam on the negative ELBO; returns (model, params, per-epoch history)."""
    if config.epochs < 1 or config.batch_size < 1:
        raise ValueError(
            f"epochs and batch_size must be >= 1, got {config.epochs}, {config.batch_size}"
        )
    model = make_model(config, data.num_classes)
    key = jax.random.key(config.seed)
    init_key, key = jax.random.split(key)
    params = init_params(model, init_key, data.x_train[:1])
    state = TrainState.create(
        apply_fn=model.apply, params=params, tx=optax.adam(config.learning_rate)
    )
    train_step = _make_train_step(model, config, len(data.x_train))
    rng = np.random.default_rng(config.seed)
    n_batches = max(1, len(data.x_train) // config.batch_size)
    history = []
    for epoch in tqdm(range(config.epochs), desc="training", disable=not progress):
        order = rng.permutation(len(data.x_train))
        sums: dict[str, float] = {}
        for b in range(n_batches):
            idx = order[b * config.batch_size : (b + 1) * config.batch_size]
            key, step_key = jax.random.split(key)
            state, metrics = train_step(state, data.x_train[idx], data.y_train[idx], step_key)
            for name, value in metrics.items():
                sums[name] = sums.get(name, 0.0) + float(value)
        history.append({"epoch": epoch + 1, **{k: v / n_batches for k, v in sums.items()}})
    return model, state.params, history


def innate_accuracy(
    model: SGBMLP, params: Any, x: np.ndarray, y: np.ndarray, key: jax.Array, n_individuals: int
) -> dict[str, Any]:
    """Test accuracy of the mean network, of each of ``n_individuals`` sampled individuals,
    and of the population's averaged prediction (mean of their softmax outputs)."""
    if n_individuals < 1:
        raise ValueError(f"n_individuals must be >= 1, got {n_individuals}")
    logits = apply_population(model, params, x, jax.random.split(key, n_individuals))
    individuals = (jnp.argmax(logits, -1) == y).mean(axis=1)
    averaged = jax.nn.softmax(logits, -1).mean(axis=0)
    return {
        "mean_network": float((jnp.argmax(apply_mean_network(model, params, x), -1) == y).mean()),
        "individuals": np.asarray(individuals).tolist(),
        "population_average": float((jnp.argmax(averaged, -1) == y).mean()),
    }


def train_and_evaluate(
    config: ClassifierConfig, data: Dataset, progress: bool = True
) -> dict[str, Any]:
    """Train, then evaluate innately on the test set. Returns params, history, accuracies."""
    model, params, history = train_classifier(config, data, progress)
    accuracy = innate_accuracy(
        model,
        params,
        data.x_test,
        data.y_test,
        jax.random.key(config.seed + 10_000),
        config.eval_individuals,
    )
    return {"model": model, "params": params, "history": history, "accuracy": accuracy}
