"""The one minibatch training loop, used by the SGB, the DGB and the uncompressed network,
and the steps it runs.

``train_loop`` draws shuffled minibatches (a fresh permutation each epoch, the last
partial batch dropped), runs ``step(state, x, y, key) -> (state, metrics)`` on each
and, every ``hook_every`` steps, ``hook(state) -> state`` (the DGB's write-backs).
It returns the state and one record per epoch of the metrics' means.
"""

from collections.abc import Callable
from functools import partial
from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax.training.train_state import TrainState
from tqdm.auto import tqdm

from sgb import validation
from sgb.divergence import Guard, likely_cause
from sgb.elbo import cross_entropy, elbo_loss

DataLoss = Callable[[jnp.ndarray, jnp.ndarray], jnp.ndarray]
Step = Callable[[Any, jnp.ndarray, jnp.ndarray, jax.Array], tuple[Any, dict]]


def train_loop(
    state: Any,
    step: Step,
    x: np.ndarray,
    y: np.ndarray,
    *,
    batch_size: int,
    num_steps: int,
    seed: int,
    hook: Callable[[Any], Any] | None = None,
    hook_every: int = 0,
    params_of: Callable[[Any], Any] = lambda state: state.params,
    progress: bool = True,
    desc: str = "training",
    num_classes: int | None = None,
    guard: Guard | None = None,
) -> tuple[Any, list[dict[str, float]]]:
    """Run ``num_steps`` minibatch steps of ``batch_size`` examples of (x, y).

    Returns the final state and per-epoch records ``{"epoch", **mean metrics}``
    (the last one over a partial epoch if ``num_steps`` is not a whole number of epochs).
    ``x`` must be non-empty and finite, ``y`` as long (finite, or with ``num_classes``
    integer labels in [0, num_classes)): checked once, before the first step.
    ``guard`` (``sgb.divergence.Guard``; default: a fresh one that names rho overflow or
    the learning rate as the likely cause) raises ``sgb.divergence.TrainingDiverged`` at the
    first step whose ``metrics["loss"]`` is not finite or blew up, and if the final
    ``params_of(state)`` holds a non-finite value; ``hook`` may use it too.
    """
    validation.integer("num_steps", num_steps)
    validation.integer("batch_size", batch_size)
    validation.seed("seed", seed)
    if hook is not None and (isinstance(hook_every, bool) or not hook_every >= 1):
        raise ValueError(f"hook_every must be >= 1 with a hook, got {hook_every}")
    x = validation.finite_array("x", x, min_ndim=1)
    if num_classes is not None:
        y = validation.labels("y", y, validation.integer("num_classes", num_classes))
    else:
        y = validation.finite_array("y", y, min_ndim=1)
    if len(y) != len(x):
        raise ValueError(f"x and y must hold as many examples, got {len(x)} and {len(y)}")
    current = {"state": state}
    if guard is None:
        guard = Guard(cause=lambda: likely_cause(params=params_of(current["state"])))
    rng = np.random.default_rng(seed)
    key = jax.random.key(seed)
    n_batches = max(1, len(x) // batch_size)
    history: list[dict[str, float]] = []
    sums: dict[str, Any] = {}
    count = 0
    order = rng.permutation(len(x))
    for t in tqdm(range(num_steps), desc=desc, disable=not progress):
        b = t % n_batches
        if b == 0 and t > 0:
            order = rng.permutation(len(x))
        idx = order[b * batch_size : (b + 1) * batch_size]
        key, step_key = jax.random.split(key)
        state, metrics = step(state, x[idx], y[idx], step_key)
        current["state"] = state
        guard.loss(metrics["loss"], t + 1)
        sums = {k: sums.get(k, 0.0) + v for k, v in metrics.items()}
        count += 1
        if hook is not None and (t + 1) % hook_every == 0:
            state = current["state"] = hook(state)
        if b == n_batches - 1 or t == num_steps - 1:
            means = {k: float(v) / count for k, v in sums.items()}
            history.append({"epoch": (t + 1) / n_batches, **means})
            sums, count = {}, 0
    guard.params(params_of(state), num_steps)
    return state, history


def adam_state(apply_fn: Callable, params: Any, learning_rate: float) -> TrainState:
    """A flax ``TrainState`` of ``params`` with Adam at ``learning_rate``.

    Its step counter is an int32 array, not flax's Python 0, so a jitted step returns a
    state of the signature it was given and compiles once, not twice.
    """
    state = TrainState.create(apply_fn=apply_fn, params=params, tx=optax.adam(learning_rate))
    return state.replace(step=jnp.zeros((), jnp.int32))


def accuracy(logits: jnp.ndarray, labels: jnp.ndarray) -> jnp.ndarray:
    """Fraction of examples whose largest logit is the label."""
    return jnp.mean(jnp.argmax(logits, -1) == labels)


def cross_entropy_step(state: TrainState, x, y, key) -> tuple[TrainState, dict]:
    """One Adam step of a deterministic classifier on cross-entropy (``key`` unused)."""
    del key
    loss, grads = jax.value_and_grad(lambda p: cross_entropy(state.apply_fn(p, x), y))(state.params)
    return state.apply_gradients(grads=grads), {"loss": loss}


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
    num_classes: int | None = None,
) -> tuple[Any, list[dict[str, float]]]:
    """Train an SGB model's ``params`` on the negative ELBO with Adam for ``epochs`` passes.

    Returns the trained params and one dict per epoch with the mean ``loss``,
    ``data`` and ``kl`` terms over its minibatches. ``local_reparam`` selects the
    gradient estimator of ``sgb.elbo.elbo_loss``; ``num_classes``, when given, is checked
    against the labels ``y`` (``train_loop``).
    """
    validation.integer("epochs", epochs)
    validation.integer("batch_size", batch_size)
    validation.integer("num_samples", num_samples)
    validation.non_negative("kl_weight", kl_weight)
    validation.positive("learning_rate", learning_rate)
    validation.array("x", x, min_ndim=1)
    own = jax.tree_util.tree_map(jnp.copy, params)  # own buffers, so steps can donate them
    state = adam_state(model.apply, own, learning_rate)

    @partial(jax.jit, donate_argnums=0)
    def elbo_step(state: TrainState, xb, yb, key):
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

    steps = epochs * max(1, len(x) // batch_size)
    state, history = train_loop(
        state,
        elbo_step,
        x,
        y,
        batch_size=batch_size,
        num_steps=steps,
        seed=seed,
        progress=progress,
        num_classes=num_classes,
    )
    return state.params, history
