"""Actor and critic networks, vanilla or SGB, and the individuals they make.

Both networks are MLPs (swish between layers). In SGB mode the hidden layers
are ``sgb.layers.SGBDense`` layers whose neurons fall into ``cell_types``
types (the input layer keeps one type per observation entry) and the output
layer is an ordinary deterministic ``nn.Dense``, as in the paper. The authors'
code does two things more, each a switch here: ``typed_inputs`` groups the
observation entries into types too, and ``sgb_output`` makes the output layer an
SGB layer (``min(cell_types, n)`` types for n neurons). In vanilla mode every
layer is ``nn.Dense``.

An individual is a *phenotype*: the list of (kernel, bias) of every layer,
drawn once from the genome with a PRNG key and then used unchanged for a whole
episode. Its weight noise is drawn by the SGB layers (``draw_noise``), so a key
gives the same individual here as in ``sgb.layers``; ``individuals`` turns noise
into phenotypes under the current genome. ``forward`` runs phenotypes; it is
the only forward pass used in training and evaluation, so the same key always
gives the same behaviour.
"""

from dataclasses import dataclass

import flax.linen as nn
import jax
import jax.numpy as jnp

from sgb import validation
from sgb.celltypes import expand_table
from sgb.layers import (
    SGBDense,
    _check_input,
    genome_kl,
    individual_kernel,
    individual_matmul,
    softplus,
)
from sgb.priors import GaussianPrior, Prior, ScaleMixturePrior

Phenotype = list[tuple[jnp.ndarray, jnp.ndarray]]
Noise = list[jnp.ndarray]  # standard normal noise of each hidden kernel
MIN_STD = 1e-3


@dataclass(frozen=True)
class NetworkConfig:
    """Shape of the actor and the critic.

    ``cell_types=None`` is the vanilla (deterministic) network; an integer
    gives SGB hidden layers with that many cell types per hidden layer.
    ``prior`` is ``"mixture"`` (scale mixture, pi=0.5, sigma1=1, sigma2=e^-6)
    or ``"gaussian"`` (N(0, 0.1^2)). ``typed_inputs`` groups the observation entries into
    ``cell_types`` types; ``sgb_output`` makes the output layer an SGB layer. ``mean_init``
    is the standard deviation of the initial type means; ``None``: 1/sqrt(n_in) of each
    layer.
    """

    hidden: tuple[int, ...] = (128, 128)
    cell_types: int | None = None
    prior: str = "mixture"
    rho_init: float = -5.0
    typed_inputs: bool = False
    sgb_output: bool = False
    mean_init: float | None = None

    def __post_init__(self) -> None:
        validation.integers("hidden", self.hidden)
        validation.real("rho_init", self.rho_init)
        validation.instance("typed_inputs", self.typed_inputs, bool)
        validation.instance("sgb_output", self.sgb_output, bool)
        if self.mean_init is not None:
            validation.positive("mean_init", self.mean_init)
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
    """``in_features`` -> hidden layers (SGB or dense) -> ``out`` units (dense, or SGB
    with ``sgb_output``). Layers are named ``hidden_0``, ``hidden_1``, ... and ``out``.
    An input of another width than ``in_features`` is a ``ValueError``."""

    config: NetworkConfig
    out: int
    in_features: int

    @nn.compact
    def __call__(self, x: jnp.ndarray, mean_network: bool = False) -> jnp.ndarray:
        cfg = self.config
        _check_input(x, self.in_features)
        sgb = sgb_layers(self)
        widths = (*cfg.hidden, self.out)
        for i, (name, width) in enumerate(zip(layer_names(cfg), widths, strict=True)):
            if name in sgb:
                k_in = None if i == 0 and not cfg.typed_inputs else cfg.cell_types
                n_in = x.shape[-1]
                layer = SGBDense(
                    width,
                    in_types=None if k_in is None else min(k_in, n_in),
                    out_types=min(cfg.cell_types, width),
                    prior=_prior(cfg),
                    mean_init_std=1.0 if cfg.mean_init is None else cfg.mean_init * n_in**0.5,
                    rho_init=cfg.rho_init,
                    in_features=(self.in_features, *cfg.hidden)[i],
                    name=name,
                )
                x = layer(x, mean_network)
            else:
                x = nn.Dense(width, name=name)(x)
            if i < len(cfg.hidden):
                x = nn.swish(x)
        return x


def layer_names(config: NetworkConfig) -> list[str]:
    """Names of the layers of an ``MLP``, input to output."""
    return [f"hidden_{i}" for i in range(len(config.hidden))] + ["out"]


def sgb_layers(model: MLP) -> dict[str, tuple[int, int]]:
    """The SGB layers of ``model`` and their kernel shapes (n_in, n_out), input to output."""
    cfg = model.config
    if not cfg.sgb:
        return {}
    widths = (model.in_features, *cfg.hidden, model.out)
    shapes = dict(zip(layer_names(cfg), zip(widths[:-1], widths[1:], strict=True), strict=True))
    if not cfg.sgb_output:
        del shapes["out"]
    return shapes


def _prior(config: NetworkConfig) -> Prior:
    """The weight prior named in ``config``."""
    return GaussianPrior(0.1) if config.prior == "gaussian" else ScaleMixturePrior()


def draw_noise(model: MLP, params: dict, key: jax.Array) -> Noise | None:
    """The noise of the individual drawn with ``key``: per SGB layer, shape (n_in, n_out).

    Drawn by the SGB layers themselves (``sgb.layers.sample_kernel``), so key ``k``
    gives here the individual that ``model.apply(params, x, rngs={"sample": k})`` is.
    ``None`` for vanilla networks, which have no noise. vmap it for many keys.
    """
    if not model.config.sgb:
        return None
    dummy = jnp.zeros((1, model.in_features))
    _, state = model.apply(params, dummy, rngs={"sample": key}, mutable=["individual"])
    drawn = state["individual"]
    return [drawn[name]["genome"]["noise"] for name in sgb_layers(model)]


def individuals(model: MLP, params: dict, noise: Noise | None) -> Phenotype:
    """Phenotypes from ``noise`` (``draw_noise`` vmapped: leading axis N).

    Each SGB kernel is ``sgb.layers.individual_kernel(mu, rho, noise)``, shape
    (N, n_in, n_out), differentiable in ``params`` (reparameterised); the other kernels
    and the biases are shared by all N. For ``noise=None`` (vanilla networks, or the mean
    network) returns the one deterministic phenotype, every kernel shared.
    """
    p = params["params"]
    shapes = sgb_layers(model)
    by_layer = dict(zip(shapes, noise, strict=True)) if noise is not None else {}

    def kernel(name: str) -> jnp.ndarray:
        if name not in shapes:
            return p[name]["kernel"]
        genome = p[name]["genome"]
        if noise is None:
            return expand_table(genome["mu"], shapes[name])
        return individual_kernel(genome["mu"], genome["rho"], by_layer[name])

    return [(kernel(name), p[name]["bias"]) for name in layer_names(model.config)]


def network_kl(model: MLP, params: dict, key: jax.Array) -> jnp.ndarray:
    """KL of the network's genome to its prior, a scalar (nats): ``sgb.layers.genome_kl``
    of every SGB layer, synapses counted; 0 for vanilla networks."""
    shapes = sgb_layers(model)
    if not shapes:
        return jnp.zeros(())
    prior = _prior(model.config)
    keys = jax.random.split(key, len(shapes))
    genomes = [params["params"][name]["genome"] for name in shapes]
    return sum(
        genome_kl(prior, g["mu"], softplus(g["rho"]), shape, "synapse", k)
        for g, shape, k in zip(genomes, shapes.values(), keys, strict=True)
    )


def drawn_individuals(model: MLP, params: dict, keys: jax.Array | None) -> Phenotype:
    """``individuals`` of the keys (N, 2), one each; ``keys=None``: the mean network."""
    if keys is None:
        return individuals(model, params, None)
    noise = jax.vmap(lambda k: draw_noise(model, params, k))(keys)
    return individuals(model, params, noise)


def forward(layers: Phenotype, x: jnp.ndarray) -> jnp.ndarray:
    """Run phenotypes on inputs ``x`` (..., n_in) -> (..., n_out).

    A kernel (n_in, n_out) is shared by every input; a kernel (N, n_in, n_out) holds one
    individual per row of ``x`` (N, ..., n_in).
    """
    for i, (kernel, bias) in enumerate(layers):
        if kernel.ndim == 2:
            x = x @ kernel + bias
        else:
            x = individual_matmul(x, kernel) + bias
        if i < len(layers) - 1:
            x = nn.swish(x)
    return x


def action_distribution(logits: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
    """Split actor outputs (..., 2 * act) into Gaussian loc and scale (softplus + 1e-3).

    Not a spread: ``jax.nn.softplus``, exact over the whole float32 range (the spreads'
    ``sgb.layers.softplus`` saturates above 88)."""
    loc, raw = jnp.split(logits, 2, axis=-1)
    return loc, jax.nn.softplus(raw) + MIN_STD


def tanh_gaussian_log_prob(u: jnp.ndarray, loc: jnp.ndarray, scale: jnp.ndarray) -> jnp.ndarray:
    """log-density of the action tanh(u) where u ~ N(loc, scale^2), summed over the last axis."""
    log_normal = -0.5 * ((u - loc) / scale) ** 2 - jnp.log(scale) - 0.5 * jnp.log(2 * jnp.pi)
    return jnp.sum(log_normal - _log_det_tanh(u), axis=-1)


def tanh_gaussian_entropy(scale: jnp.ndarray, u: jnp.ndarray) -> jnp.ndarray:
    """One-draw estimate of the entropy of the action tanh(u), u ~ N(loc, scale^2), at a draw
    ``u``, summed over the last axis (nats): the Gaussian's entropy plus log|d tanh(u)/du|.

    The second term penalises saturating the tanh, so the entropy bonus cannot be bought
    by widening the Gaussian beyond the action range.
    """
    gaussian = 0.5 + 0.5 * jnp.log(2 * jnp.pi) + jnp.log(scale)
    return jnp.sum(gaussian + _log_det_tanh(u), axis=-1)


def _log_det_tanh(u: jnp.ndarray) -> jnp.ndarray:
    """log|d tanh(u)/du| = log(1 - tanh(u)^2), elementwise, computed stably."""
    return 2.0 * (jnp.log(2.0) - u - jax.nn.softplus(-2.0 * u))
