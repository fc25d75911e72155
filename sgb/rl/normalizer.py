"""Running mean and variance of observations, merged batch by batch (Chan et al.), and the
two conventions for scaling observations by them.

``"ours"``: std = sqrt(M2 / (n - 1) + 1e-6), observations left unchanged until two were
seen. ``"authors"`` (``RL/models.py`` of ``self-supervisor/genomic_bottleneck_v2``,
``normalize``): variance = clip(M2 / (n + 1), 1e-6, 1e6), applied from the start, so that
before the first update (M2 = 0) the std is 1e-3 and every input is clipped to +-5. Both
clip the scaled observations to [-5, 5]. Their ``update_normalization`` is the same
merge (its mean step and its M2 step are Chan's, rewritten); what differs is what they
count: every unroll's T + 1 observations, the bootstrap one too
(``sgb.rl.trainer.Trainer.seen``).
"""

from typing import NamedTuple

import jax.numpy as jnp

CONVENTIONS = ("ours", "authors")


class Normalizer(NamedTuple):
    """Count, mean (obs,) and sum of squared deviations (obs,) of the observations seen."""

    count: jnp.ndarray
    mean: jnp.ndarray
    m2: jnp.ndarray


def init_normalizer(size: int) -> Normalizer:
    """An empty normalizer for observations of ``size`` entries."""
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


def normalize(norm: Normalizer, obs: jnp.ndarray, convention: str = "ours") -> jnp.ndarray:
    """(obs - mean) / std, clipped to [-5, 5], under ``convention`` (module docstring):
    ``"ours"`` is the identity until two observations were seen."""
    if convention == "authors":
        std = jnp.sqrt(jnp.clip(norm.m2 / (norm.count + 1.0), 1e-6, 1e6))
        return jnp.clip((obs - norm.mean) / std, -5.0, 5.0)
    std = jnp.sqrt(norm.m2 / jnp.maximum(norm.count - 1.0, 1.0) + 1e-6)
    scaled = jnp.clip((obs - norm.mean) / std, -5.0, 5.0)
    return jnp.where(norm.count > 1, scaled, obs)
