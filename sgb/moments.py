"""The moment-matched mean network of an SGB MLP: pre-activation means and variances
propagated through the genome's Gaussian weights, layer by layer.

An individual's weight ``w_ij`` is drawn independently from N(M_ij, S_ij^2), with ``M`` and
``S`` its type pair's mean and spread (``sgb.genome``: S = softplus(rho)). For a layer
a = x @ W + b whose inputs ``x_i`` are independent of each other and of ``W``, with means
``m_x`` and variances ``v_x``, the pre-activations have

    E[a]   = m_x @ M + b,
    Var[a] = v_x @ (M^2 + S^2) + m_x^2 @ S^2.

Between layers the classifier applies a ReLU (``sgb.layers.SGBMLP``); for a ~ N(m, s^2)

    E[relu(a)]   = m Phi(m/s) + s phi(m/s),
    E[relu(a)^2] = (m^2 + s^2) Phi(m/s) + m s phi(m/s),

with Phi and phi the standard normal CDF and density. Each hidden pre-activation is taken
to be Gaussian with the propagated mean and variance.

For a deterministic input and one hidden layer this is exact, not an approximation: the
hidden pre-activations are linear in the Gaussian weights, so Gaussian, and independent of
each other (each column of the first kernel is drawn on its own); the output's mean and
variance then follow from the formula above without approximation. The output mean is then
the expectation of the logits over individuals. With more hidden layers the hidden units of
the second and later layers share their inputs, so they are correlated and not Gaussian,
and the propagated moments are approximations.

The moment-matched network predicts the argmax of the output mean. With every spread zero
it is the mean network (every weight at its mean), computed by the same operations.
"""

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax.scipy.stats import norm

from sgb import genome
from sgb.celltypes import block_counts, expand_table


class GaussianLayer(NamedTuple):
    """One dense SGB layer: type tables ``mu`` and ``sigma`` (k_in, k_out), the spread
    sigma = softplus(rho), and ``bias`` (n_out,)."""

    mu: jnp.ndarray
    sigma: jnp.ndarray
    bias: jnp.ndarray


class Moments(NamedTuple):
    """Elementwise means and variances of a batch of activations, each (..., n)."""

    mean: jnp.ndarray
    var: jnp.ndarray


def relu_moments(mean: jnp.ndarray, var: jnp.ndarray) -> Moments:
    """Mean and variance of relu(a) for a ~ N(mean, var), elementwise; any equal shapes.

    Where ``var`` is zero the result is relu(mean) and variance zero, exactly. The
    variance is computed as s^2 g(z), z = m / s, with g written so that no term cancels
    a larger one when |z| is large:
    g = z^2 Phi(z) Phi(-z) + Phi(z) + z phi(z) (Phi(-z) - Phi(z)) - phi(z)^2.
    """
    mean, var = jnp.asarray(mean), jnp.asarray(var)
    std = jnp.sqrt(jnp.maximum(var, 0.0))
    noisy = std > 0
    safe_std = jnp.where(noisy, std, 1.0)
    z = mean / safe_std
    cdf, cdf_minus, pdf = norm.cdf(z), norm.cdf(-z), norm.pdf(z)
    first = mean * cdf + safe_std * pdf
    g = z**2 * cdf * cdf_minus + cdf + z * pdf * (cdf_minus - cdf) - pdf**2
    second = safe_std**2 * jnp.maximum(g, 0.0)
    return Moments(jnp.where(noisy, first, jnp.maximum(mean, 0.0)), jnp.where(noisy, second, 0.0))


def dense_moments(inputs: Moments, layer: GaussianLayer) -> Moments:
    """Moments of the pre-activations a = x @ W + b of one layer, (..., n_out), for inputs
    ``x`` with elementwise ``inputs`` (..., n_in), independent of each other and of the
    weights, and weights drawn per synapse from the layer's type tables.

    The mean is ``m_x @ expand(mu) + b``, the same product the layer's mean network computes.
    """
    n_in, n_out = inputs.mean.shape[-1], layer.bias.shape[-1]
    means = expand_table(layer.mu, (n_in, n_out))
    variances = expand_table(layer.sigma**2, (n_in, n_out))
    mean = inputs.mean @ means + layer.bias
    var = inputs.var @ (means**2 + variances) + inputs.mean**2 @ variances
    return Moments(mean, var)


def propagate(layers: list[GaussianLayer], x: jnp.ndarray) -> list[Moments]:
    """Moments of every layer's pre-activations for deterministic inputs ``x`` (..., n_in),
    a ReLU between layers (none after the last); item i is layer i's, (..., n_out_i)."""
    x = jnp.asarray(x)
    activations = Moments(x, jnp.zeros_like(x))
    out = []
    for i, layer in enumerate(layers):
        pre = dense_moments(activations, layer)
        out.append(pre)
        if i < len(layers) - 1:
            activations = relu_moments(*pre)
    return out


def moment_logits(layers: list[GaussianLayer], x: jnp.ndarray) -> Moments:
    """Moments of the output (logits) for inputs ``x`` (..., n_in): (..., classes)."""
    return propagate(layers, x)[-1]


def without_noise(layers: list[GaussianLayer]) -> list[GaussianLayer]:
    """The same layers with every spread zero: their propagation is the mean network."""
    return [layer._replace(sigma=jnp.zeros_like(layer.sigma)) for layer in layers]


def mlp_layers(params: Any) -> list[GaussianLayer]:
    """The dense layers of an ``sgb.layers.SGBMLP``'s ``{"params": ...}``, in order.

    The spread is softplus(rho) as the layers draw it. An MLP has layers ``SGBDense_0``,
    ``SGBDense_1``, ...; a conv classifier's deterministic trunk is not covered (pass its
    head's params with the trunk's features as inputs).
    """
    inner = params["params"]
    tables = genome.of_params(params)
    return [
        GaussianLayer(tables[name].mu, genome.sigma(tables[name]), inner[name]["bias"])
        for name in _layer_names(inner)
    ]


def _layer_names(inner: dict) -> list[str]:
    """``SGBDense_0``, ``SGBDense_1``, ... of an SGBMLP's params, in order of depth."""
    names = sorted((k for k in inner if k.startswith("SGBDense_")), key=lambda k: int(k[9:]))
    if not names or len(names) != len(inner):
        raise ValueError(f"not the params of an SGBMLP: layers {sorted(inner)}")
    return names


@jax.jit
def _predictions(layers: list[GaussianLayer], x: jnp.ndarray) -> jnp.ndarray:
    return jnp.argmax(moment_logits(layers, x).mean, axis=-1)


def moment_accuracy(params: Any, x: jnp.ndarray, y: jnp.ndarray) -> float:
    """Accuracy of the moment-matched network of an SGBMLP's ``params`` on ``x`` (n, n_in)
    with labels ``y`` (n,): the argmax of the output mean."""
    return float((_predictions(mlp_layers(params), jnp.asarray(x)) == jnp.asarray(y)).mean())


def layer_statistics(params: Any, in_features: int) -> list[dict[str, float]]:
    """Per dense layer of an SGBMLP's ``params`` (inputs of width ``in_features``): the
    per-synapse means of |mu|, sigma and rho (each type pair weighted by its synapses) and
    the layer's shape (n_in, n_out) and type table (k_in, k_out)."""
    stats = []
    n_in = in_features
    for name, layer in zip(_layer_names(params["params"]), mlp_layers(params), strict=True):
        n_out = int(layer.bias.shape[-1])
        counts = jnp.asarray(block_counts((n_in, n_out), layer.mu.shape), jnp.float32)
        rho = genome.of_params(params)[name].rho

        def average(table: jnp.ndarray, counts: jnp.ndarray = counts) -> float:
            return float(jnp.sum(table * counts) / jnp.sum(counts))

        stats.append(
            {
                "layer": name,
                "shape": [n_in, n_out],
                "types": [int(k) for k in layer.mu.shape],
                "mean_abs_mu": average(jnp.abs(layer.mu)),
                "mean_sigma": average(layer.sigma),
                "mean_rho": average(rho),
            }
        )
        n_in = n_out
    return stats
