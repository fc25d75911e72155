"""A generic minibatch loop that trains an SGB model's genome on the negative ELBO with Adam."""

from collections.abc import Callable
from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax.training.train_state import TrainState
from tqdm.auto import tqdm

from sgb import validation
from sgb.divergence import check_loss, check_params
from sgb.elbo import elbo_loss

DataLoss = Callable[[jnp.ndarray, jnp.ndarray], jnp.ndarray]


def fit_elbo(
    model: nn.Module,
    params: Any,
    x: np.ndarray,
    y: np.ndarray,
    *,
    data_loss: DataLoss,
    kl_weight: float,
    num_samples: int,
    learning_rate: float,
    batch_size: int,
    epochs: int,
    seed: int,
    local_reparam: bool = False,
    progress: bool = True,
) -> tuple[Any, list[dict[str, float]]]:
    """Train ``params`` on (x, y) for ``epochs`` passes of shuffled minibatches.

    Returns the trained params and one dict per epoch with the mean ``loss``,
    ``data`` and ``kl`` terms over its minibatches. ``local_reparam`` selects the
    gradient estimator of ``sgb.elbo.elbo_loss``. Raises ``sgb.divergence.TrainingDiverged``
    at the first step whose loss is not finite.
    """
    validation.integer("epochs", epochs)
    validation.integer("batch_size", batch_size)
    validation.integer("num_samples", num_samples)
    validation.positive("learning_rate", learning_rate)
    validation.non_negative("kl_weight", kl_weight)
    state = TrainState.create(apply_fn=model.apply, params=params, tx=optax.adam(learning_rate))

    @jax.jit
    def train_step(state: TrainState, xb, yb, key):
        def loss_fn(p):
            return elbo_loss(
                model,
                p,
                xb,
                yb,
                key,
                num_samples=num_samples,
                kl_weight=kl_weight,
                data_loss=data_loss,
                local_reparam=local_reparam,
            )

        (loss, parts), grads = jax.value_and_grad(loss_fn, has_aux=True)(state.params)
        return state.apply_gradients(grads=grads), {"loss": loss, **parts}

    rng = np.random.default_rng(seed)
    key = jax.random.key(seed)
    n_batches = max(1, len(x) // batch_size)
    history = []
    for epoch in tqdm(range(epochs), desc="training", disable=not progress):
        order = rng.permutation(len(x))
        sums: dict[str, float] = {}
        for b in range(n_batches):
            idx = order[b * batch_size : (b + 1) * batch_size]
            key, step_key = jax.random.split(key)
            state, metrics = train_step(state, x[idx], y[idx], step_key)
            check_loss(float(metrics["loss"]), epoch * n_batches + b + 1)
            for name, value in metrics.items():
                sums[name] = sums.get(name, 0.0) + float(value)
        history.append({"epoch": epoch + 1, **{k: v / n_batches for k, v in sums.items()}})
    check_params(state.params, epochs * n_batches)
    return state.params, history
