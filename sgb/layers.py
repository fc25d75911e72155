"""SGB layers (Flax linen): a genome of per-type-pair means and spreads, sampled per synapse.

A layer holds a type table ``mu`` and ``rho`` (sigma = softplus(rho)) and per-neuron
biases; ``sgb.genome`` holds the functions that develop a kernel from them and reads
them back (``sgb.genome.of_params``). Each call draws every synapse's weight
independently from its type pair's Gaussian, or uses the means alone when
``mean_network=True``. The ``"sample"`` key a model is applied with is the individual's
key: a layer of ``index`` i draws its noise from ``sgb.genome.layer_key(key, i)`` and its
Monte Carlo KL from ``layer_key(kl_key(key), i)``, as ``sgb.genome.draw_noise`` and
``sgb.genome.kl`` do, so one key gives one individual on both paths (the layers of one
model need distinct indices; ``SGBMLP`` numbers its own). The KL term of the layer is sown into
the ``"losses"`` collection and the drawn kernel and its standard normal
noise into ``"individual"`` (each apply replaces what an earlier one sowed).
``sgb.individuals.init_params`` initialises a model's parameters alone.

With as many types as neurons the layer is a Bayes-by-backprop layer; with one
type per side, one distribution for the whole layer.

``SGBDense`` and ``SGBMLP`` also take ``local_reparam=True`` (Kingma, Salimans and
Welling, 2015): instead of one weight matrix shared by the batch, each example's
pre-activations are drawn from their exact Gaussian, mean x @ mu and variance
x^2 @ sigma^2, summed over type blocks so the full matrix is never formed. Every
example then sees its own independent weights: an unbiased, lower-variance estimate
of the ELBO's data term for training, but not an individual (evaluate individuals
with the default path).
"""

from collections.abc import Sequence

import flax.linen as nn
import jax
import jax.numpy as jnp

from sgb import validation
from sgb.celltypes import assign_cell_types, expand_table, type_sizes
from sgb.genome import (
    KL_COUNTINGS,
    KLCounting,
    draw_layer_noise,
    individual_kernel,
    kl_key,
    layer_key,
    layer_kl,
    softplus,
)
from sgb.priors import PRIOR_TYPES, GaussianPrior, Prior


def _check_types(name: str, types: int, neurons: int) -> None:
    if types > neurons:
        raise ValueError(f"{name}={types} cell types is more than the {neurons} neurons")


def _check_genome_settings(module: nn.Module) -> None:
    """The genome fields every SGB layer and model shares: prior, KL counting, rho_init."""
    validation.instance("prior", module.prior, PRIOR_TYPES)
    validation.choice("kl_counting", module.kl_counting, KL_COUNTINGS)
    validation.real("rho_init", module.rho_init)


def _check_input(x: jnp.ndarray, expected: int | None) -> int:
    """Width of the last axis of ``x``, checked against ``expected`` when it is given."""
    if jnp.ndim(x) < 1:
        raise ValueError(f"inputs need a feature axis, got an array of shape {jnp.shape(x)}")
    width = x.shape[-1]
    if expected is not None and width != expected:
        raise ValueError(f"the layer is built for in_features={expected} inputs, got {width}")
    return width


def _sum_by_type(x: jnp.ndarray, types: int) -> jnp.ndarray:
    """(..., n) -> (..., types): the sum of each cell type's contiguous block of neurons."""
    n = x.shape[-1]
    if types == n:
        return x
    ids = jnp.asarray(assign_cell_types(n, types))
    summed = jax.ops.segment_sum(jnp.moveaxis(x, -1, 0), ids, types, indices_are_sorted=True)
    return jnp.moveaxis(summed, 0, -1)


def type_matmul(x: jnp.ndarray, table: jnp.ndarray, features: int) -> jnp.ndarray:
    """``x @ expand_table(table, (n_in, features))`` without forming the full matrix.

    ``x``: (..., n_in); ``table``: (k_in, k_out). Returns (..., features), at a cost of
    O(n_in + k_in * k_out + features) per example instead of O(n_in * features).
    """
    k_in, k_out = table.shape
    y = _sum_by_type(x, k_in) @ table
    if k_out == features:
        return y
    return jnp.repeat(y, type_sizes(features, k_out), axis=-1, total_repeat_length=features)


@jax.custom_vjp
def individual_matmul(x: jnp.ndarray, kernels: jnp.ndarray) -> jnp.ndarray:
    """Each individual's inputs times its own kernel: ``x`` (N, ..., n_in) and ``kernels``
    (N, n_in, n_out) -> (N, ..., n_out), row n of ``x`` through kernel n.

    The gradient is the plain one, laid out for XLA on CPU: both batched products of the
    backward pass read an operand transposed once and held (``optimization_barrier``).
    Without the barrier XLA folds the transpose into a strided product, which took 1.6 to
    1.8 times as long for 32 individuals of 16 x 128 inputs and 128 x 128 kernels (the
    SGB-PPO update's shapes) on a 2-core CPU.
    """
    return jnp.einsum("n...i,nij->n...j", x, kernels)


def _individual_matmul_forward(x, kernels):
    return individual_matmul(x, kernels), (x, kernels)


def _individual_matmul_backward(residuals, grad):
    x, kernels = residuals
    n = x.shape[0]
    rows_x = x.reshape(n, -1, x.shape[-1])  # (N, rows, n_in)
    rows_grad = grad.reshape(n, -1, grad.shape[-1])  # (N, rows, n_out)
    x_t = jax.lax.optimization_barrier(jnp.swapaxes(rows_x, 1, 2))
    d_kernels = jnp.einsum("nir,nrj->nij", x_t, rows_grad)
    dx_t = jax.lax.optimization_barrier(jnp.einsum("nij,nrj->nir", kernels, rows_grad))
    return jnp.swapaxes(dx_t, 1, 2).reshape(x.shape), d_kernels


individual_matmul.defvjp(_individual_matmul_forward, _individual_matmul_backward)


def _individual_key(module: nn.Module) -> jax.Array:
    """The ``"sample"`` key the model was applied with (``"params"``'s without one, as
    ``make_rng`` falls back): the key of the individual it draws."""
    name = "sample" if module.has_rng("sample") else "params"
    if not module.has_rng(name):
        raise ValueError('an SGB layer draws its weights from the "sample" PRNG stream')
    return module.scope.rngs[name].rng


def _replace(_previous, new):
    """Sow reducer that keeps only the latest value, so repeated applies never accumulate."""
    return new


def _rho_initializer(mean: float, std: float):
    """Raw spreads drawn from N(mean, std^2); exactly ``mean`` where ``std`` is 0."""
    if std == 0:
        return nn.initializers.constant(mean)

    def init(key, shape, dtype=jnp.float32):
        return mean + std * jax.random.normal(key, shape, dtype)

    return init


class _GenomeKernel(nn.Module):
    """Samples a kernel of ``shape`` from a type table of ``types``; sows its KL. ``index``:
    its place among the model's drawn layers (``sgb.genome.layer_key``)."""

    shape: tuple[int, ...]
    types: tuple[int, ...]
    prior: Prior
    kl_counting: KLCounting
    mean_init_std: float
    rho_init: float
    rho_init_std: float = 0.0
    index: int = 0

    @nn.compact
    def __call__(
        self, mean_network: bool, tables_only: bool = False
    ) -> jnp.ndarray | tuple[jnp.ndarray, jnp.ndarray]:
        """The drawn kernel (the mean kernel if ``mean_network``); with ``tables_only``,
        the type tables (mu, sigma) instead. Sows the KL (``sgb.genome.layer_kl``) when sampling."""
        mu = self.param("mu", nn.initializers.normal(self.mean_init_std), self.types)
        rho = self.param("rho", _rho_initializer(self.rho_init, self.rho_init_std), self.types)
        sigma = softplus(rho)
        if tables_only:
            if not mean_network:
                self._sow_kl(mu, sigma)
            return mu, sigma
        if mean_network:
            kernel = expand_table(mu, self.shape)
        else:
            noise = draw_layer_noise(layer_key(_individual_key(self), self.index), self.shape)
            kernel = individual_kernel(mu, rho, noise)
            self._sow_kl(mu, sigma)
            self.sow("individual", "noise", noise, init_fn=lambda: None, reduce_fn=_replace)
        self.sow("individual", "kernel", kernel, init_fn=lambda: None, reduce_fn=_replace)
        return kernel

    def _sow_kl(self, mu: jnp.ndarray, sigma: jnp.ndarray) -> None:
        key = layer_key(kl_key(_individual_key(self)), self.index)
        kl = layer_kl(self.prior, mu, sigma, self.shape, self.kl_counting, key)
        self.sow("losses", "kl", kl, init_fn=lambda: None, reduce_fn=_replace)


class _BayesianBias(nn.Module):
    """Biases (features,) drawn per neuron from a genome of shape (1, features), the
    model's drawn layer ``index``."""

    features: int
    prior: Prior
    kl_counting: KLCounting
    mean_init_std: float
    rho_init: float
    rho_init_std: float = 0.0
    index: int = 0

    @nn.compact
    def __call__(self, mean_network: bool) -> jnp.ndarray:
        shape = (1, self.features)
        genome = _GenomeKernel(
            shape,
            shape,
            self.prior,
            self.kl_counting,
            self.mean_init_std,
            self.rho_init,
            self.rho_init_std,
            self.index,
            name="genome",
        )
        return genome(mean_network)[0]


class SGBDense(nn.Module):
    """Dense layer (..., n_in) -> (..., features) with a (in_types, out_types) genome.

    ``in_types``/``out_types`` of ``None`` mean one type per neuron.
    ``mean_init_std`` is in units of 1/sqrt(n_in). ``in_features``, when given, is the
    input width the layer is built for: a type table fits any width, so without it an
    input of another width would run unnoticed. ``bayesian_bias`` draws the biases too,
    each neuron's from its own Gaussian (a genome of shape (1, features) at the layer's
    path + ``/bias``, means starting with the kernel means' standard deviation), as the
    authors' RL layers do (``RL/custom_layers.py``); otherwise they are plain parameters.
    Every raw spread starts at ``rho_init`` plus N(0, ``rho_init_std``^2) (exactly
    ``rho_init`` at the default 0). ``index``: the kernel's place among the model's drawn
    layers (``sgb.genome.layer_key``), the Bayesian biases' ``index + 1``.
    """

    features: int
    in_types: int | None = None
    out_types: int | None = None
    prior: Prior = GaussianPrior(0.1)
    kl_counting: KLCounting = "synapse"
    mean_init_std: float = 1.0
    rho_init: float = -5.0
    in_features: int | None = None
    bayesian_bias: bool = False
    rho_init_std: float = 0.0
    index: int = 0

    def __post_init__(self) -> None:
        validation.integer("features", self.features)
        validation.integer("index", self.index, minimum=0)
        validation.non_negative("rho_init_std", self.rho_init_std)
        validation.instance("bayesian_bias", self.bayesian_bias, bool)
        for name in ("in_types", "out_types", "in_features"):
            if getattr(self, name) is not None:
                validation.integer(name, getattr(self, name))
        validation.non_negative("mean_init_std", self.mean_init_std)
        _check_genome_settings(self)
        super().__post_init__()

    @nn.compact
    def __call__(
        self, x: jnp.ndarray, mean_network: bool = False, local_reparam: bool = False
    ) -> jnp.ndarray:
        n_in = _check_input(x, self.in_features)
        k_in = n_in if self.in_types is None else self.in_types
        k_out = self.features if self.out_types is None else self.out_types
        _check_types("in_types", k_in, n_in)
        _check_types("out_types", k_out, self.features)
        genome = _GenomeKernel(
            shape=(n_in, self.features),
            types=(k_in, k_out),
            prior=self.prior,
            kl_counting=self.kl_counting,
            mean_init_std=self.mean_init_std / n_in**0.5,
            rho_init=self.rho_init,
            rho_init_std=self.rho_init_std,
            index=self.index,
            name="genome",
        )
        if self.bayesian_bias:
            if local_reparam:
                raise ValueError("local_reparam draws pre-activations; it takes no bayesian_bias")
            bias = _BayesianBias(
                self.features,
                self.prior,
                self.kl_counting,
                self.mean_init_std / n_in**0.5,
                self.rho_init,
                self.rho_init_std,
                self.index + 1,
                name="bias",
            )(mean_network)
        else:
            bias = self.param("bias", nn.initializers.zeros, (self.features,))
        if not local_reparam:
            return x @ genome(mean_network) + bias
        mu, sigma = genome(mean_network, tables_only=True)
        y = type_matmul(x, mu, self.features) + bias
        if mean_network:
            return y
        variance = type_matmul(x**2, sigma**2, self.features)
        noise = jax.random.normal(self.make_rng("sample"), y.shape, y.dtype)
        return y + jnp.sqrt(jnp.maximum(variance, 1e-30)) * noise


class SGBConv(nn.Module):
    """2-D convolution, NHWC, with a 4-D genome: types along (height, width, c_in, c_out);
    ``index`` its place among the model's drawn layers (``sgb.genome.layer_key``)."""

    features: int
    kernel_size: tuple[int, int]
    types: tuple[int, int, int, int]
    strides: tuple[int, int] = (1, 1)
    padding: str = "SAME"
    prior: Prior = GaussianPrior(0.1)
    kl_counting: KLCounting = "synapse"
    mean_init_std: float = 1.0
    rho_init: float = -5.0
    index: int = 0

    def __post_init__(self) -> None:
        validation.integer("features", self.features)
        validation.integer("index", self.index, minimum=0)
        if len(validation.integers("kernel_size", self.kernel_size)) != 2:
            raise ValueError(f"kernel_size must have 2 entries, got {self.kernel_size}")
        if len(validation.integers("types", self.types)) != 4:
            raise ValueError(f"types must have 4 entries (h, w, c_in, c_out), got {self.types}")
        validation.integers("strides", self.strides)
        validation.choice("padding", self.padding, ("SAME", "VALID"))
        validation.non_negative("mean_init_std", self.mean_init_std)
        _check_genome_settings(self)
        super().__post_init__()

    @nn.compact
    def __call__(self, x: jnp.ndarray, mean_network: bool = False) -> jnp.ndarray:
        if jnp.ndim(x) != 4:
            raise ValueError(f"inputs must be NHWC (4 axes), got shape {jnp.shape(x)}")
        shape = (*self.kernel_size, x.shape[-1], self.features)
        names = ("height types", "width types", "input-channel types", "output-channel types")
        for name, k, n in zip(names, self.types, shape, strict=True):
            _check_types(name, k, n)
        fan_in = shape[0] * shape[1] * shape[2]
        kernel = _GenomeKernel(
            shape=shape,
            types=tuple(self.types),
            prior=self.prior,
            kl_counting=self.kl_counting,
            mean_init_std=self.mean_init_std / fan_in**0.5,
            rho_init=self.rho_init,
            index=self.index,
            name="genome",
        )(mean_network)
        y = jax.lax.conv_general_dilated(
            x, kernel, self.strides, self.padding, dimension_numbers=("NHWC", "HWIO", "NHWC")
        )
        bias = self.param("bias", nn.initializers.zeros, (self.features,))
        return y + bias


class SGBMLP(nn.Module):
    """MLP of SGB layers with ReLU between them.

    ``widths``: output width of each layer, e.g. (800, 10).
    ``cell_types``: types of each neuron layer including the input, length
    len(widths) + 1, e.g. (30, 64, 10); ``None`` entries mean one type per neuron.
    ``in_features``: the input width, checked on every call when given (every model the
    package builds gives it); each further layer checks the width of the one before.
    Layer i is the model's drawn layer i (``sgb.genome.layer_key``).
    """

    widths: Sequence[int]
    cell_types: Sequence[int | None]
    prior: Prior = GaussianPrior(0.1)
    kl_counting: KLCounting = "synapse"
    rho_init: float = -5.0
    in_features: int | None = None

    def __post_init__(self) -> None:
        widths = validation.integers("widths", self.widths)
        types = validation.integers("cell_types", self.cell_types, allow_none=True)
        if len(types) != len(widths) + 1:
            raise ValueError(
                f"cell_types needs {len(widths) + 1} entries (input and every layer), "
                f"got {len(types)}"
            )
        for i, (k, n) in enumerate(zip(types[1:], widths, strict=True)):
            if k is not None:
                _check_types(f"cell_types[{i + 1}]", k, n)
        if self.in_features is not None:
            validation.integer("in_features", self.in_features)
        _check_genome_settings(self)
        super().__post_init__()

    @nn.compact
    def __call__(
        self, x: jnp.ndarray, mean_network: bool = False, local_reparam: bool = False
    ) -> jnp.ndarray:
        _check_input(x, self.in_features)
        for i, width in enumerate(self.widths):
            x = SGBDense(
                width,
                in_types=self.cell_types[i],
                out_types=self.cell_types[i + 1],
                prior=self.prior,
                kl_counting=self.kl_counting,
                rho_init=self.rho_init,
                in_features=self.in_features if i == 0 else self.widths[i - 1],
                index=i,
            )(x, mean_network, local_reparam)
            if i < len(self.widths) - 1:
                x = nn.relu(x)
        return x
