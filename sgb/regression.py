"""1-D regression with a Bayesian MLP: toy data, a Gaussian likelihood and predictive bands."""

from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np

from sgb.individuals import apply_population


def toy_regression_data(
    n: int = 64, noise: float = 0.1, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """``n`` points y = sin(3x) + noise on two clusters x in [-1, -0.35] and [0.35, 1].

    The gap between the clusters is where a Bayesian network should be unsure.
    Returns x, y of shape (n, 1), float32.
    """
    if n < 2 or noise < 0:
        raise ValueError(f"need n >= 2 and noise >= 0, got n={n}, noise={noise}")
    rng = np.random.default_rng(seed)
    x = np.concatenate([rng.uniform(-1, -0.35, n // 2), rng.uniform(0.35, 1, n - n // 2)])
    y = np.sin(3 * x) + noise * rng.standard_normal(n)
    return x[:, None].astype(np.float32), y[:, None].astype(np.float32)


def gaussian_nll(noise: float):
    """Data term: mean negative log-likelihood of y ~ N(prediction, noise^2), nats per point."""
    if noise <= 0:
        raise ValueError(f"noise must be > 0, got {noise}")

    def data_loss(prediction: jnp.ndarray, y: jnp.ndarray) -> jnp.ndarray:
        return jnp.mean(0.5 * ((prediction - y) / noise) ** 2 + jnp.log(noise))

    return data_loss


def predictive_bands(
    model: nn.Module, params: Any, x: np.ndarray, key: jax.Array, n_individuals: int = 200
) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation over ``n_individuals`` sampled networks, each shape (len(x),)."""
    outputs = np.asarray(apply_population(model, params, x, jax.random.split(key, n_individuals)))
    return outputs[..., 0].mean(axis=0), outputs[..., 0].std(axis=0)
