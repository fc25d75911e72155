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

Params = Any


def init_params(model: nn.Module, key: jax.Array, x: jnp.ndarray) -> Params:
    """Initial ``{"params": ...}`` of ``model`` for inputs like ``x``, without sown state."""
    init_key, sample_key = jax.random.split(key)
    variables = model.init({"params": init_key, "sample": sample_key}, x)
    return {"params": variables["params"]}


@partial(jax.jit, static_argnums=0)
def apply_mean_network(model: nn.Module, params: Params, x: jnp.ndarray):
    """Output of the mean network (every weight at its type pair's mean)."""
    return model.apply(params, x, mean_network=True)


@partial(jax.jit, static_argnums=0)
def apply_population(model: nn.Module, params: Params, x: jnp.ndarray, keys: jax.Array):
    """Outputs of one individual per key, shape (N, *output shape) for N keys."""
    return jax.vmap(lambda key: model.apply(params, x, rngs={"sample": key}))(keys)


def individual_kernels(
    model: nn.Module, params: Params, x: jnp.ndarray, key: jax.Array | None
) -> dict:
    """The kernels of one individual (or of the mean network for ``key=None``), by layer."""
    if key is None:
        _, state = model.apply(params, x, mean_network=True, mutable=["individual"])
    else:
        _, state = model.apply(params, x, rngs={"sample": key}, mutable=["individual"])
    return state["individual"]
