"""Individuals, the mean network and populations of an SGB model.

An individual is one draw of every weight, fixed by its PRNG key: the same
key always gives the same individual. A population of N individuals is
evaluated with ``jax.vmap`` over N keys in one jitted call.
"""

from functools import partial
from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp

from sgb import genome, validation

Params = Any


def _check(model: nn.Module, x: Any) -> jnp.ndarray:
    """The checks every entry point makes: a flax module and finite inputs ``x``."""
    validation.instance("model", model, nn.Module)
    return validation.finite_array("x", x, min_ndim=1)


def init_params(model: nn.Module, key: jax.Array, x: jnp.ndarray) -> Params:
    """Initial ``{"params": ...}`` of ``model`` for inputs like ``x``, without sown state."""
    return _init_params(model, validation.prng_key("key", key), _check(model, x))


@partial(jax.jit, static_argnums=0)
def _init_params(model: nn.Module, key: jax.Array, x: jnp.ndarray) -> Params:
    init_key, sample_key = jax.random.split(key)
    variables = model.init({"params": init_key, "sample": sample_key}, x)
    return {"params": variables["params"]}


def apply_mean_network(model: nn.Module, params: Params, x: jnp.ndarray):
    """Output of the mean network (every weight at its type pair's mean)."""
    return _apply_mean_network(model, params, _check(model, x))


def apply_population(model: nn.Module, params: Params, x: jnp.ndarray, keys: jax.Array):
    """Outputs of one individual per key, shape (N, *output shape) for N keys."""
    x = _check(model, x)
    keys = validation.prng_key("keys", keys)
    if jnp.ndim(keys) != (1 if jax.dtypes.issubdtype(keys.dtype, jax.dtypes.prng_key) else 2):
        raise ValueError(f"keys must be a 1-D array of keys (jax.random.split), got {keys!r}")
    return _apply_population(model, params, x, keys)


@partial(jax.jit, static_argnums=0)
def _apply_mean_network(model: nn.Module, params: Params, x: jnp.ndarray):
    return model.apply(params, x, mean_network=True)


@partial(jax.jit, static_argnums=0)
def _apply_population(model: nn.Module, params: Params, x: jnp.ndarray, keys: jax.Array):
    return jax.vmap(lambda key: model.apply(params, x, rngs={"sample": key}))(keys)


def individual_kernels(
    model: nn.Module, params: Params, x: jnp.ndarray, key: jax.Array | None
) -> dict:
    """The kernels of one individual (or of the mean network for ``key=None``), by layer
    path (``sgb.genome.of_params``'s keys)."""
    x = _check(model, x)
    if key is None:
        _, state = model.apply(params, x, mean_network=True, mutable=["individual"])
    else:
        validation.prng_key("key", key)
        _, state = model.apply(params, x, rngs={"sample": key}, mutable=["individual"])
    return genome.sown(state["individual"], "kernel")
