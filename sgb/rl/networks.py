"""Actor and critic networks, vanilla or SGB, and the individuals they make.

Both networks are MLPs (swish between layers). In SGB mode the hidden layers
are ``sgb.layers.SGBDense`` layers whose neurons fall into ``cell_types``
types (the input layer keeps one type per observation entry) and the output
layer is an ordinary deterministic ``nn.Dense``, as in the paper. In vanilla
mode every layer is ``nn.Dense``.

An individual is a *phenotype*: the list of (kernel, bias) of every layer,
drawn once from the genome with a PRNG key and then used unchanged for a whole
episode. ``forward`` runs a phenotype; it is the only forward pass used in
training and evaluation, so the same key always gives the same behaviour.
"""

from dataclasses import dataclass

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np

from sgb import validation
from sgb.celltypes import assign_cell_types
from sgb.layers import SGBDense
from sgb.priors import GaussianPrior, Prior, ScaleMixturePrior

Phenotype = list[tuple[jnp.ndarray, jnp.ndarray]]
MIN_STD = 1e-3


@dataclass(frozen=True)
class NetworkConfig:
    """Shape of the actor and the critic.

    ``cell_types=None`` is the vanilla (deterministic) network; an integer
    gives SGB hidden layers with that many cell types per hidden layer.
    ``prior`` is ``"mixture"`` (scale mixture, pi=0.5, sigma1=1, sigma2=e^-6)
    or ``"gaussian"`` (N(0, 0.1^2)).
    """

    hidden: tuple[int, ...] = (128, 128)
    cell_types: int | None = None
    prior: str = "mixture"
    rho_init: float = -5.0

    def __post_init__(self) -> None:
        validation.integers("hidden", self.hidden)
        validation.real("rho_init", self.rho_init)
        if self.cell_types is not None and not (
            0 < validation.integer("cell_types", self.cell_types) <= min(self.hidden)
        ):
            raise ValueError(
                f"cell_types must lie in [1, {min(self.hidden)}], got {self.cell_types}"
            )
        if self.prior not in ("mixture", "gaussian"):
            raise ValueError(f"prior must be 'mixture' or 'gaussian', got {self.prior!r}")

    @property
    def sgb(self) -> bool:
        return self.cell_types is not None


class MLP(nn.Module):
    """Hidden layers (SGB or dense) and a deterministic dense output layer of ``out`` units."""

    config: NetworkConfig
    out: int

    @nn.compact
    def __call__(self, x: jnp.ndarray, mean_network: bool = False) -> jnp.ndarray:
        cfg = self.config
        prior = _prior(cfg)
        for i, width in enumerate(cfg.hidden):
            if cfg.sgb:
                layer = SGBDense(
                    width,
                    in_types=None if i == 0 else cfg.cell_types,
                    out_types=cfg.cell_types,
                    prior=prior,
                    rho_init=cfg.rho_init,
                    name=f"hidden_{i}",
                )
                x = nn.swish(layer(x, mean_network))
            else:
                x = nn.swish(nn.Dense(width, name=f"hidden_{i}")(x))
        return nn.Dense(self.out, name="out")(x)


def _membership(n: int, k: int) -> jnp.ndarray:
    """One-hot cell-type membership (n, k) of n neurons in k contiguous balanced types."""
    return jnp.asarray(np.eye(k, dtype=np.float32)[assign_cell_types(n, k)])


def _prior(config: NetworkConfig) -> Prior:
    """The weight prior named in ``config``."""
    return GaussianPrior(0.1) if config.prior == "gaussian" else ScaleMixturePrior()


def phenotype(
    model: MLP, params: dict, key: jax.Array | None, obs_size: int
) -> tuple[Phenotype, jnp.ndarray]:
    """The individual drawn with ``key`` (``None``: the mean network) and its KL (nats).

    Returns the list of (kernel (n_in, n_out), bias (n_out,)) of every layer
    and the Monte Carlo KL of this draw to the prior, summed over synapses
    (log q(w) - log p(w), as in Bayes by backprop; 0 for vanilla networks and
    the mean network). Differentiable in ``params`` (reparameterised).

    A hidden layer's kernel is M_in mu M_out^T + (M_in sigma M_out^T) * eps
    with one-hot type memberships M and eps ~ N(0, 1) drawn from
    ``fold_in(key, layer)``: the same distribution as ``sgb.layers.SGBDense``
    (whose mean network it reproduces exactly), written with matrix products
    so that gradients of many individuals at once stay cheap on a CPU.
    """
    cfg, p = model.config, params["params"]
    layers, kl, n_in = [], jnp.zeros(()), obs_size
    for i, width in enumerate(cfg.hidden):
        layer = p[f"hidden_{i}"]
        if not cfg.sgb:
            layers.append((layer["kernel"], layer["bias"]))
            continue
        mu, rho = layer["genome"]["mu"], layer["genome"]["rho"]
        m_in, m_out = _membership(n_in, mu.shape[0]), _membership(width, mu.shape[1])
        kernel = m_in @ mu @ m_out.T
        if key is not None:
            sigma = m_in @ jax.nn.softplus(rho) @ m_out.T
            eps = jax.random.normal(jax.random.fold_in(key, i), kernel.shape)
            kernel = kernel + sigma * eps
            log_q = jnp.sum(-0.5 * eps**2 - jnp.log(sigma) - 0.5 * jnp.log(2 * jnp.pi))
            kl = kl + log_q - jnp.sum(_prior(cfg).log_prob(kernel))
        layers.append((kernel, layer["bias"]))
        n_in = width
    layers.append((p["out"]["kernel"], p["out"]["bias"]))
    return layers, kl


def individuals(
    model: MLP, params: dict, keys: jax.Array | None, obs_size: int
) -> tuple[Phenotype, jnp.ndarray]:
    """Phenotypes of one individual per key (leading axis N) and their KLs, shape (N,).

    For vanilla networks, or ``keys=None`` (the mean network), returns the one
    deterministic phenotype without a leading axis and KL 0; ``apply`` then
    shares it across the batch.
    """
    if model.config.sgb and keys is not None:
        return jax.vmap(lambda k: phenotype(model, params, k, obs_size))(keys)
    return phenotype(model, params, None, obs_size)


def apply(layers: Phenotype, x: jnp.ndarray, batched: bool) -> jnp.ndarray:
    """Run phenotypes on ``x`` (N, ..., n_in): one per row if ``batched``, else one shared."""
    return jax.vmap(forward)(layers, x) if batched else forward(layers, x)


def forward(layers: Phenotype, x: jnp.ndarray) -> jnp.ndarray:
    """Run a phenotype on inputs ``x`` (..., n_in) -> (..., n_out)."""
    for kernel, bias in layers[:-1]:
        x = nn.swish(x @ kernel + bias)
    kernel, bias = layers[-1]
    return x @ kernel + bias


def action_distribution(logits: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Split actor outputs (..., 2 * act) into Gaussian loc and scale (softplus + 1e-3)."""
    loc, raw = jnp.split(logits, 2, axis=-1)
    return loc, jax.nn.softplus(raw) + MIN_STD


def tanh_gaussian_log_prob(u: jnp.ndarray, loc: jnp.ndarray, scale: jnp.ndarray) -> jnp.ndarray:
    """log-density of the action tanh(u) where u ~ N(loc, scale^2), summed over the last axis."""
    log_normal = -0.5 * ((u - loc) / scale) ** 2 - jnp.log(scale) - 0.5 * jnp.log(2 * jnp.pi)
    log_det = 2.0 * (jnp.log(2.0) - u - jax.nn.softplus(-2.0 * u))
    return jnp.sum(log_normal - log_det, axis=-1)


def gaussian_entropy(scale: jnp.ndarray) -> jnp.ndarray:
    """Entropy of the pre-tanh Gaussian, summed over the last axis (nats)."""
    return jnp.sum(0.5 + 0.5 * jnp.log(2 * jnp.pi) + jnp.log(scale), axis=-1)
