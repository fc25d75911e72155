"""Classifier modules: the deterministic p-net (uncompressed network and DGB) and the SGB
classifier, each an optional deterministic conv trunk followed by a dense stack.

Each takes the shape of one example it is built for (``input_shape``), and refuses an
input of another shape with a ``ValueError`` that names both; the package always gives
it (``None`` leaves it unchecked)."""

from collections.abc import Sequence
from typing import Any

import flax.linen as nn
import jax.numpy as jnp
import numpy as np

from sgb.genome import KLCounting
from sgb.layers import SGBMLP
from sgb.priors import GaussianPrior, Prior


class ConvTrunk(nn.Module):
    """Deterministic conv trunk (N, H, W, C) -> (N, features); identity on (N, features)
    when ``features`` is empty."""

    features: Sequence[int] = ()

    @nn.compact
    def __call__(self, x: jnp.ndarray) -> jnp.ndarray:
        if not self.features:
            return x
        for width in self.features:
            x = nn.max_pool(nn.relu(nn.Conv(width, (3, 3))(x)), (2, 2), (2, 2))
        return x.reshape(x.shape[0], -1)


def check_input_shape(x: jnp.ndarray, input_shape: Sequence[int] | None) -> None:
    """Raise ``ValueError`` unless ``x`` is a batch of examples of ``input_shape``."""
    if input_shape is None:
        return
    shape = tuple(jnp.shape(x))
    if len(shape) < 1 or shape[1:] != tuple(input_shape):
        raise ValueError(
            f"the network is built for a batch of inputs of shape {tuple(input_shape)}, "
            f"got an array of shape {shape}"
        )


class DenseClassifier(nn.Module):
    """Conv trunk, then dense layers ``dense_0..`` of ``widths`` with ReLU between them."""

    widths: Sequence[int]
    conv_features: Sequence[int] = ()
    input_shape: Sequence[int] | None = None

    @nn.compact
    def __call__(self, x: jnp.ndarray) -> jnp.ndarray:
        check_input_shape(x, self.input_shape)
        x = ConvTrunk(tuple(self.conv_features), name="trunk")(x)
        for i, width in enumerate(self.widths):
            x = nn.Dense(width, name=f"dense_{i}")(x)
            if i < len(self.widths) - 1:
                x = nn.relu(x)
        return x


class SGBConvClassifier(nn.Module):
    """Deterministic conv trunk, then an ``SGBMLP`` head (the only stochastic part)."""

    conv_features: Sequence[int]
    widths: Sequence[int]
    cell_types: Sequence[int | None]
    prior: Prior = GaussianPrior(0.1)
    kl_counting: KLCounting = "synapse"
    rho_init: float = -5.0
    input_shape: Sequence[int] | None = None

    @nn.compact
    def __call__(
        self, x: jnp.ndarray, mean_network: bool = False, local_reparam: bool = False
    ) -> jnp.ndarray:
        check_input_shape(x, self.input_shape)
        x = ConvTrunk(tuple(self.conv_features), name="trunk")(x)
        head = SGBMLP(
            self.widths, self.cell_types, self.prior, self.kl_counting, self.rho_init, name="head"
        )
        return head(x, mean_network, local_reparam)


def sgb_classifier(
    widths: Sequence[int],
    cell_types: Sequence[int | None],
    prior: Prior,
    kl_counting: KLCounting,
    rho_init: float,
    conv_features: Sequence[int] = (),
    input_shape: Sequence[int] | None = None,
) -> nn.Module:
    """An ``SGBMLP`` of ``widths`` (with a conv trunk when ``conv_features`` is not empty)
    for examples of ``input_shape`` (the MLP's: one axis, its input width)."""
    shape = None if input_shape is None else tuple(int(n) for n in input_shape)
    if not conv_features:
        if shape is not None and len(shape) != 1:
            raise ValueError(f"an SGB MLP takes feature vectors, not inputs of shape {shape}")
        width = None if shape is None else shape[0]
        return SGBMLP(widths, cell_types, prior, kl_counting, rho_init, in_features=width)
    return SGBConvClassifier(
        tuple(conv_features), widths, cell_types, prior, kl_counting, rho_init, input_shape=shape
    )


def dense_sizes(
    input_shape: Sequence[int], conv_features: Sequence[int], hidden: Sequence[int], classes: int
) -> tuple[int, ...]:
    """Layer sizes of the dense stack, e.g. (784, 800, 10); ``input_shape`` excludes the batch."""
    if conv_features:
        if len(input_shape) != 3:
            raise ValueError(
                f"conv_features need (height, width, channels) inputs, got {input_shape}"
            )
        h, w = input_shape[0], input_shape[1]
        for _ in conv_features:
            h, w = h // 2, w // 2
        features = h * w * conv_features[-1]
    else:
        features = int(np.prod(input_shape))
    return (int(features), *hidden, classes)


def with_kernels(params: Any, kernels: Sequence[jnp.ndarray]) -> Any:
    """``params`` of a ``DenseClassifier`` with its dense kernels replaced."""
    inner = dict(params["params"])
    for i, kernel in enumerate(kernels):
        inner[f"dense_{i}"] = {**inner[f"dense_{i}"], "kernel": kernel}
    return {**params, "params": inner}
