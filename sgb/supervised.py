"""Supervised training and innate (zero-shot) evaluation of the three classifiers.

* SGB (``ClassifierConfig``): trained on the negative ELBO (``sgb.training.fit_elbo``);
  innate accuracy is that of sampled individuals, beside the mean network's.
* DGB (``sgb.dgb.DGBConfig``): trained by ``sgb.dgb.train_dgb``; innate accuracy is that
  of the network its g-nets generate.
* Uncompressed (``DenseConfig``): the p-net trained on cross-entropy alone.

``train_and_evaluate(config, data)`` is the one call for any of them. Its result flags a
network whose test accuracy is no better than chance (``at_chance``) rather than report
it silently; the data are checked before training (``sgb.data.check_dataset``) and every
evaluation's inputs before it runs.
"""

import dataclasses
from functools import partial
from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np

from sgb import validation
from sgb.classifiers import DenseClassifier, sgb_classifier
from sgb.data import Dataset, check_dataset
from sgb.dgb import DGBConfig, train_dgb
from sgb.elbo import cross_entropy
from sgb.genome import KL_COUNTINGS, KLCounting
from sgb.individuals import apply_mean_network, apply_population, init_params
from sgb.priors import PRIOR_TYPES, GaussianPrior, Prior
from sgb.training import adam_state, cross_entropy_step, fit_elbo, train_loop


def _check_training(config: "ClassifierConfig | DenseConfig") -> None:
    """The optimisation settings both configs share, and the network's shape."""
    validation.integers("hidden", config.hidden)
    validation.positive("learning_rate", config.learning_rate)
    validation.integer("batch_size", config.batch_size)
    validation.integer("epochs", config.epochs)
    validation.integer("seed", config.seed, minimum=0)
    if config.conv_features:
        validation.integers("conv_features", config.conv_features)


@dataclasses.dataclass(frozen=True)
class ClassifierConfig:
    """An SGB classifier and its training.

    ``hidden``: hidden widths; ``cell_types``: types of the input, each hidden
    layer and the output (``None`` = one type per neuron, a plain BNN layer).
    ``conv_features``: output channels of deterministic 3x3 conv + 2x2 max-pool
    layers before the dense stack (empty: none, the input is a feature vector).
    ``kl_scale`` multiplies the per-example KL weight 1/n_train. ``local_reparam`` trains
    with per-example pre-activation noise (``sgb.layers``); evaluation always samples
    whole individuals.
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
    conv_features: tuple[int, ...] = ()
    local_reparam: bool = False

    def __post_init__(self) -> None:
        _check_training(self)
        types = validation.integers("cell_types", self.cell_types, allow_none=True)
        if len(types) != len(self.hidden) + 2:
            raise ValueError(
                f"cell_types needs {len(self.hidden) + 2} entries (input, every hidden layer, "
                f"output), got {len(types)}"
            )
        validation.instance("prior", self.prior, PRIOR_TYPES)
        validation.choice("kl_counting", self.kl_counting, KL_COUNTINGS)
        validation.non_negative("kl_scale", self.kl_scale)
        validation.real("rho_init", self.rho_init)
        validation.integer("num_samples", self.num_samples)
        validation.integer("eval_individuals", self.eval_individuals)
        validation.instance("local_reparam", self.local_reparam, bool)


# Chapter 3's digits classifiers (64 inputs, 32 hidden units, 10 outputs; 2,368 weights):
# one type per neuron, and 16/8/10 types.
DIGITS_CLASSIFIERS = (
    ClassifierConfig(hidden=(32,), cell_types=(None, None, None), epochs=20, learning_rate=3e-3),
    ClassifierConfig(hidden=(32,), cell_types=(16, 8, 10), epochs=20, learning_rate=3e-3),
)


@dataclasses.dataclass(frozen=True)
class DenseConfig:
    """The uncompressed deterministic classifier and its training."""

    hidden: tuple[int, ...] = (64,)
    learning_rate: float = 1e-3
    batch_size: int = 64
    epochs: int = 20
    seed: int = 0
    conv_features: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        _check_training(self)


def make_model(
    config: ClassifierConfig, num_classes: int, input_shape: tuple[int, ...]
) -> nn.Module:
    """The SGB classifier a config describes (an ``SGBMLP`` without conv layers), for
    examples of ``input_shape`` (one example's, no batch axis), checked on every call: a
    layer's genome is a type table, whose shape does not tell the input width it was
    made for."""
    validation.instance("config", config, ClassifierConfig)
    return sgb_classifier(
        (*config.hidden, validation.integer("num_classes", num_classes)),
        config.cell_types,
        config.prior,
        config.kl_counting,
        config.rho_init,
        config.conv_features,
        validation.integers("input_shape", input_shape),
    )


def train_classifier(
    config: ClassifierConfig, data: Dataset, progress: bool = True
) -> tuple[nn.Module, Any, list[dict[str, float]]]:
    """Train an SGB classifier with Adam on the negative ELBO; returns (model, params,
    per-epoch history of loss, data term and KL)."""
    check_dataset(data)
    model = make_model(config, data.num_classes, data.x_train.shape[1:])
    params = init_params(model, jax.random.key(config.seed), data.x_train[:1])
    params, history = fit_elbo(
        model,
        params,
        data.x_train,
        data.y_train,
        data_loss=cross_entropy,
        kl_weight=config.kl_scale / len(data.x_train),
        num_samples=config.num_samples,
        learning_rate=config.learning_rate,
        batch_size=config.batch_size,
        epochs=config.epochs,
        seed=config.seed,
        local_reparam=config.local_reparam,
        progress=progress,
        num_classes=data.num_classes,
    )
    return model, params, history


def train_dense(
    config: DenseConfig, data: Dataset, progress: bool = True
) -> tuple[nn.Module, Any, list[dict[str, float]]]:
    """Train the uncompressed network on cross-entropy; returns (model, params, history)."""
    validation.instance("config", config, DenseConfig)
    check_dataset(data)
    model = DenseClassifier(
        (*config.hidden, data.num_classes), config.conv_features, data.x_train.shape[1:]
    )
    params = model.init(jax.random.key(config.seed), data.x_train[:1])
    state = adam_state(model.apply, params, config.learning_rate)
    state, history = train_loop(
        state,
        jax.jit(cross_entropy_step, donate_argnums=0),  # steps update the state in place
        data.x_train,
        data.y_train,
        batch_size=config.batch_size,
        num_steps=config.epochs * max(1, len(data.x_train) // config.batch_size),
        seed=config.seed,
        progress=progress,
        desc="uncompressed training",
        num_classes=data.num_classes,
    )
    return model, state.params, history


def _check_eval(x: Any, y: Any) -> tuple[Any, Any]:
    """Test inputs ``x`` (non-empty, finite) and as many integer labels ``y`` (>= 0)."""
    x = validation.finite_array("x", x, min_ndim=2)
    y = validation.labels("y", y)
    if tuple(y.shape) != (len(x),):
        raise ValueError(f"y must hold one label per example of x ({len(x)}), got shape {y.shape}")
    return x, y


def _check_classes(logits: jnp.ndarray, y: Any) -> None:
    """Labels ``y`` must name one of the network's ``logits.shape[-1]`` classes."""
    validation.labels("y", y, logits.shape[-1])


def chance_level(y: np.ndarray) -> float:
    """The accuracy of always guessing the most common of the labels ``y``."""
    y = np.asarray(y)
    return float(np.bincount(y).max() / y.size)


def at_chance(accuracy: float, y: np.ndarray) -> bool:
    """Whether ``accuracy`` on labels ``y`` is no better than chance (``chance_level``): not
    above it by three binomial standard errors of a guess on ``len(y)`` examples."""
    p = chance_level(y)
    return bool(accuracy <= p + 3.0 * np.sqrt(p * (1.0 - p) / np.size(y)))


def innate_accuracy(
    model: nn.Module, params: Any, x: np.ndarray, y: np.ndarray, key: jax.Array, n_individuals: int
) -> dict[str, Any]:
    """Test accuracy of the mean network, of each of ``n_individuals`` sampled individuals,
    and of the population's averaged prediction (mean of their softmax outputs)."""
    validation.integer("n_individuals", n_individuals)
    validation.prng_key("key", key)
    x, y = _check_eval(x, y)
    logits = apply_population(model, params, x, jax.random.split(key, n_individuals))
    _check_classes(logits, y)
    individuals = (jnp.argmax(logits, -1) == y).mean(axis=1)
    averaged = jax.nn.softmax(logits, -1).mean(axis=0)
    return {
        "mean_network": float((jnp.argmax(apply_mean_network(model, params, x), -1) == y).mean()),
        "individuals": np.asarray(individuals).tolist(),
        "population_average": float((jnp.argmax(averaged, -1) == y).mean()),
    }


def dense_accuracy(model: nn.Module, params: Any, x: np.ndarray, y: np.ndarray) -> float:
    """Test accuracy of a deterministic ``DenseClassifier`` (DGB or uncompressed)."""
    x, y = _check_eval(x, y)
    logits = _dense_logits(model, {"params": params["params"]}, x)
    _check_classes(logits, y)
    return float((jnp.argmax(logits, -1) == y).mean())


@partial(jax.jit, static_argnums=0)
def _dense_logits(model: nn.Module, params: Any, x: np.ndarray) -> jnp.ndarray:
    """``model``'s logits (n, classes), compiled once per model and input shape."""
    return model.apply(params, x)


def train_and_evaluate(
    config: ClassifierConfig | DGBConfig | DenseConfig, data: Dataset, progress: bool = True
) -> dict[str, Any]:
    """Train the classifier ``config`` describes, then evaluate it innately on the test set.

    Returns ``model``, ``params`` (the innate network's), ``history`` and
    ``accuracy``: for an SGB the dict of ``innate_accuracy``, otherwise a float. A DGB's
    result also holds ``validation_accuracy``, ``fit_mse`` and ``genome`` (its g-nets).
    Every result holds ``chance`` (``chance_level`` of the test labels) and ``at_chance``
    (``at_chance`` of the accuracy, for an SGB its individuals' mean): a network that
    learnt nothing is flagged, not reported as a result like any other.
    """
    if not isinstance(config, ClassifierConfig | DGBConfig | DenseConfig):
        raise TypeError(f"no classifier for a config of type {type(config).__name__}")
    check_dataset(data)
    if isinstance(config, ClassifierConfig):
        model, params, history = train_classifier(config, data, progress)
        key = jax.random.key(config.seed + 10_000)
        accuracy = innate_accuracy(
            model, params, data.x_test, data.y_test, key, config.eval_individuals
        )
        out = {"model": model, "params": params, "history": history, "accuracy": accuracy}
        headline = float(np.mean(accuracy["individuals"]))
    elif isinstance(config, DGBConfig):
        dgb, state, history = train_dgb(config, data, progress)
        out = {
            "model": dgb.model,
            "params": state.best_params,
            "history": history,
            "accuracy": dense_accuracy(dgb.model, state.best_params, data.x_test, data.y_test),
            "validation_accuracy": float(state.best_accuracy),
            "fit_mse": float(state.fit_mse),
            "genome": state.best_gnets,
        }
        headline = out["accuracy"]
    else:
        model, params, history = train_dense(config, data, progress)
        accuracy = dense_accuracy(model, params, data.x_test, data.y_test)
        out = {"model": model, "params": params, "history": history, "accuracy": accuracy}
        headline = accuracy
    out["chance"] = chance_level(data.y_test)
    out["at_chance"] = at_chance(headline, data.y_test)
    return out
