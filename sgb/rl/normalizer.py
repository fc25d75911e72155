"""Running mean and variance of observations, merged batch by batch (Chan et al.)."""

from typing import NamedTuple

import jax.numpy as jnp


class Normalizer(NamedTuple):
    """Count, mean (obs,) and sum of squared deviations (obs,) of the observations seen."""

    count: jnp.ndarray
    mean: jnp.ndarray
    m2: jnp.ndarray


def init_normalizer(size: int) -> Normalizer:
    """An empty normalizer for observations of ``size`` entries (it leaves them unchanged)."""
    return Normalizer(jnp.zeros(()), jnp.zeros(size), jnp.zeros(size))


def update(norm: Normalizer, obs: jnp.ndarray, weight: jnp.ndarray) -> Normalizer:
    """Merge observations ``obs`` (..., size) with 0/1 ``weight`` (...) into the statistics."""
    w = weight[..., None]
    n = jnp.sum(weight)
    batch_mean = jnp.sum(obs * w, axis=tuple(range(obs.ndim - 1))) / jnp.maximum(n, 1.0)
    batch_m2 = jnp.sum(w * (obs - batch_mean) ** 2, axis=tuple(range(obs.ndim - 1)))
    total = norm.count + n
    delta = batch_mean - norm.mean
    mean = norm.mean + delta * n / jnp.maximum(total, 1.0)
    m2 = norm.m2 + batch_m2 + delta**2 * norm.count * n / jnp.maximum(total, 1.0)
    return Normalizer(total, mean, m2)


def normalize(norm: Normalizer, obs: jnp.ndarray) -> jnp.ndarray:
    """(obs - mean) / std, clipped to [-5, 5]; identity until two observations were seen."""
    std = jnp.sqrt(norm.m2 / jnp.maximum(norm.count - 1.0, 1.0) + 1e-6)
    scaled = jnp.clip((obs - norm.mean) / std, -5.0, 5.0)
    return jnp.where(norm.count > 1, scaled, obs)
