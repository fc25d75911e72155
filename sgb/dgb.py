"""Deterministic genomic bottleneck (DGB, after Koulakov et al., 2021).

Every neuron of the phenotypic network (p-net) carries a fixed code: the
binary digits of its index, as +-1 (``binary_codes``), or a one-hot vector
for the output layer. For each dense layer a small genomic network (g-net)
maps the concatenated (pre code, post code) of a synapse to its weight, so a
g-net with P parameters defines all n_pre x n_post weights of its layer.

Training (in ``sgb.supervised.train_dgb``) alternates: train the p-net for a
number of minibatches, fit the g-nets to the p-net's kernels (mean squared
error, ``fit_gnets``), write the g-nets' kernels back into the p-net
(``generate_kernels``). The innate network is the one the g-nets generate.

The genome is the g-nets' parameters plus the p-net's biases (stored
directly, as the SGB stores its biases); ``dgb_param_count`` counts them.
"""

from collections.abc import Sequence
from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import optax

from sgb.compression import dense_param_count


def binary_codes(n: int) -> np.ndarray:
    """Binary digits of 0..n-1 as +-1, shape (n, max(1, ceil(log2 n))), most significant first."""
    if int(n) != n or n <= 0:
        raise ValueError(f"n must be a positive integer, got {n!r}")
    bits = max(1, int(np.ceil(np.log2(n))))
    digits = (np.arange(n)[:, None] >> np.arange(bits - 1, -1, -1)[None, :]) & 1
    return (2.0 * digits - 1.0).astype(np.float32)


def layer_codes(sizes: Sequence[int]) -> list[np.ndarray]:
    """Codes of every neuron layer of an MLP with ``sizes``: binary, one-hot for the output."""
    if len(sizes) < 2:
        raise ValueError(f"sizes needs at least an input and an output layer, got {sizes}")
    return [binary_codes(n) for n in sizes[:-1]] + [np.eye(sizes[-1], dtype=np.float32)]


def pair_inputs(pre: np.ndarray, post: np.ndarray) -> np.ndarray:
    """G-net inputs of every synapse, shape (n_pre * n_post, bits_pre + bits_post), row-major
    in (pre, post) so that a reshape to (n_pre, n_post) gives the kernel."""
    n_pre, n_post = len(pre), len(post)
    return np.concatenate(
        [np.repeat(pre, n_post, axis=0), np.tile(post, (n_pre, 1))], axis=1
    ).astype(np.float32)


class GNet(nn.Module):
    """MLP from a synapse's (pre, post) code to its weight (before scaling): (..., d) -> (...)."""

    hidden: Sequence[int]

    @nn.compact
    def __call__(self, codes: jnp.ndarray) -> jnp.ndarray:
        x = codes
        for width in self.hidden:
            x = nn.relu(nn.Dense(width)(x))
        return nn.Dense(1)(x)[..., 0]


def gnet_param_count(code_dim: int, hidden: Sequence[int]) -> int:
    """Parameters of one ``GNet`` with ``code_dim`` inputs."""
    if any(int(h) != h or h <= 0 for h in hidden):
        raise ValueError(f"gnet hidden widths must be positive integers, got {hidden}")
    return dense_param_count((code_dim, *hidden, 1))


def dgb_param_count(sizes: Sequence[int], gnet_hidden: Sequence[int]) -> int:
    """Genome size of a DGB MLP with layer ``sizes``: all g-nets plus the p-net's biases."""
    codes = layer_codes(sizes)
    gnets = sum(
        gnet_param_count(a.shape[1] + b.shape[1], gnet_hidden)
        for a, b in zip(codes[:-1], codes[1:], strict=True)
    )
    return int(gnets + sum(sizes[1:]))


class Genome:
    """The g-nets of an MLP with layer ``sizes`` (one per dense layer) and their inputs.

    Kernels are generated as ``gnet(codes) / sqrt(n_pre)`` so that the g-nets'
    targets are of order one whatever the fan-in.
    """

    def __init__(self, sizes: Sequence[int], gnet_hidden: Sequence[int]):
        codes = layer_codes(sizes)
        self.sizes = tuple(int(s) for s in sizes)
        self.gnet = GNet(tuple(gnet_hidden))
        self.inputs = [
            jnp.asarray(pair_inputs(a, b)) for a, b in zip(codes[:-1], codes[1:], strict=True)
        ]
        self.scales = [float(n) ** -0.5 for n in self.sizes[:-1]]

    def init(self, key: jax.Array) -> list[Any]:
        """Parameters of every layer's g-net."""
        keys = jax.random.split(key, len(self.inputs))
        return [self.gnet.init(k, x[:1]) for k, x in zip(keys, self.inputs, strict=True)]

    def generate_kernels(self, gnet_params: list[Any]) -> list[jnp.ndarray]:
        """The kernels (n_pre, n_post) of every layer that the g-nets encode."""
        return [
            (self.gnet.apply(p, x) * s).reshape(a, b)
            for p, x, s, a, b in zip(
                gnet_params, self.inputs, self.scales, self.sizes[:-1], self.sizes[1:], strict=True
            )
        ]

    def fit_loss(
        self, gnet_params: list[Any], kernels: list[jnp.ndarray], key: jax.Array, batch: int
    ) -> jnp.ndarray:
        """Mean over layers of the mean squared error of kernels times sqrt(fan-in)
        (dimensionless), on ``batch`` synapses per layer drawn with ``key`` (all if fewer)."""
        errors = []
        for p, x, s, k, layer_key in zip(
            gnet_params,
            self.inputs,
            self.scales,
            kernels,
            jax.random.split(key, len(kernels)),
            strict=True,
        ):
            target = k.reshape(-1) / s
            if batch < len(x):
                idx = jax.random.randint(layer_key, (batch,), 0, len(x))
                x, target = x[idx], target[idx]
            errors.append(jnp.mean((self.gnet.apply(p, x) - target) ** 2))
        return sum(errors) / len(errors)


def make_fit(genome: Genome, optimizer: optax.GradientTransformation, steps: int, batch: int):
    """A jitted ``fit(gnet_params, opt_state, kernels, key) -> (gnet_params, opt_state, loss)``
    taking ``steps`` optimizer steps on ``genome.fit_loss`` with ``batch`` synapses per layer."""
    if steps < 1 or batch < 1:
        raise ValueError(f"steps and batch must be >= 1, got {steps}, {batch}")

    @jax.jit
    def fit(gnet_params, opt_state, kernels, key):
        def step(carry, step_key):
            params, state = carry
            loss, grads = jax.value_and_grad(genome.fit_loss)(params, kernels, step_key, batch)
            updates, state = optimizer.update(grads, state, params)
            return (optax.apply_updates(params, updates), state), loss

        (gnet_params, opt_state), losses = jax.lax.scan(
            step, (gnet_params, opt_state), jax.random.split(key, steps)
        )
        return gnet_params, opt_state, losses[-1]

    return fit


def fit_gnets(
    genome: Genome,
    kernels: list[jnp.ndarray],
    key: jax.Array,
    steps: int = 500,
    learning_rate: float = 1e-2,
    batch: int = 4096,
) -> tuple[list[Any], float]:
    """Fit fresh g-nets to given kernels with Adam; returns (g-net params, final loss)."""
    init_key, fit_key = jax.random.split(key)
    optimizer = optax.adam(learning_rate)
    params = genome.init(init_key)
    fit = make_fit(genome, optimizer, steps, batch)
    params, _, loss = fit(params, optimizer.init(params), kernels, fit_key)
    return params, float(loss)
