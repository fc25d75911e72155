"""Weight priors: a zero-mean Gaussian and the scale-mixture prior of Blundell et al. (2015).

Each prior gives the elementwise log-density of weights and the elementwise
KL divergence from a Gaussian posterior q = N(mu, sigma^2): in closed form
where it exists, otherwise the one-sample Monte Carlo estimate
log q(w) - log p(w) at a weight ``w`` drawn from q.
"""

import math
from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np
from jax.scipy.special import logsumexp

from sgb import validation

_LOG_2PI = math.log(2.0 * math.pi)


def gaussian_log_prob(w: jnp.ndarray, mean: jnp.ndarray, sigma: jnp.ndarray) -> jnp.ndarray:
    """Elementwise log N(w | mean, sigma^2)."""
    z = (w - mean) / sigma
    return -0.5 * (_LOG_2PI + z**2) - jnp.log(sigma)


@dataclass(frozen=True)
class GaussianPrior:
    """p(w) = N(w | 0, sigma^2)."""

    sigma: float = 0.1

    def __post_init__(self) -> None:
        validation.positive("sigma", self.sigma)

    def log_prob(self, w: jnp.ndarray) -> jnp.ndarray:
        return gaussian_log_prob(w, 0.0, self.sigma)

    def kl(self, mu: jnp.ndarray, sigma: jnp.ndarray, w: jnp.ndarray | None = None) -> jnp.ndarray:
        """Closed-form KL(N(mu, sigma^2) || N(0, s^2)) per element; ``w`` is ignored."""
        s2 = self.sigma**2
        return jnp.log(self.sigma / sigma) + (sigma**2 + mu**2) / (2.0 * s2) - 0.5


@dataclass(frozen=True)
class ScaleMixturePrior:
    """p(w) = pi N(w | 0, sigma1^2) + (1 - pi) N(w | 0, sigma2^2)."""

    pi: float = 0.5
    sigma1: float = 1.0
    sigma2: float = float(np.float32(math.exp(-6.0)))  # e^-6 in float32, as JAX computes it

    def __post_init__(self) -> None:
        validation.in_range("pi", self.pi, 0.0, 1.0)
        validation.positive("sigma1", self.sigma1)
        validation.positive("sigma2", self.sigma2)

    def log_prob(self, w: jnp.ndarray) -> jnp.ndarray:
        parts = jnp.stack(
            [gaussian_log_prob(w, 0.0, self.sigma1), gaussian_log_prob(w, 0.0, self.sigma2)]
        )
        weights = jnp.array([self.pi, 1.0 - self.pi]).reshape((2,) + (1,) * jnp.ndim(w))
        return logsumexp(parts, axis=0, b=weights)

    def kl(self, mu: jnp.ndarray, sigma: jnp.ndarray, w: jnp.ndarray | None = None) -> jnp.ndarray:
        """Monte Carlo KL per element, log q(w) - log p(w), at a sample ``w`` from q."""
        if w is None:
            raise ValueError("the scale-mixture KL has no closed form: pass a sample w from q")
        return gaussian_log_prob(w, mu, sigma) - self.log_prob(w)


Prior = GaussianPrior | ScaleMixturePrior
PRIOR_TYPES = (GaussianPrior, ScaleMixturePrior)
