"""Parameter counts and compression ratios, one definition for every model.

compression ratio = parameters of the uncompressed network
                    / parameters that define the compressed one.
The uncompressed network counts weights and biases. The SGB counts its means,
its rhos and its per-neuron biases; the DGB counts its g-net weights.
"""

from collections.abc import Sequence
from typing import Any

import jax
import numpy as np

from sgb import validation


def _check_sizes(sizes: Sequence[int]) -> None:
    if len(validation.integers("sizes", sizes)) < 2:
        raise ValueError(f"sizes needs at least an input and an output layer, got {sizes}")


def dense_param_count(sizes: Sequence[int]) -> int:
    """Weights and biases of a plain MLP with layer sizes e.g. (784, 800, 10)."""
    _check_sizes(sizes)
    return int(sum(a * b + b for a, b in zip(sizes[:-1], sizes[1:], strict=True)))


def sgb_param_count(sizes: Sequence[int], cell_types: Sequence[int | None]) -> int:
    """Means, rhos and biases of an SGB MLP; ``cell_types`` as in ``SGBMLP``."""
    _check_sizes(sizes)
    if len(validation.integers("cell_types", cell_types, allow_none=True)) != len(sizes):
        raise ValueError(f"cell_types {cell_types} must have one entry per layer of {sizes}")
    types = [n if k is None else k for n, k in zip(sizes, cell_types, strict=True)]
    for n, k in zip(sizes, types, strict=True):
        if not 0 < k <= n:
            raise ValueError(f"cell types must lie in [1, {n}] for a layer of {n}, got {k}")
    return int(sum(2 * a * b + n for a, b, n in zip(types[:-1], types[1:], sizes[1:], strict=True)))


def tree_param_count(params: Any) -> int:
    """Number of scalars in a parameter pytree."""
    return int(sum(np.size(leaf) for leaf in jax.tree_util.tree_leaves(params)))


def compression_ratio(uncompressed: int, compressed: int) -> float:
    """Uncompressed over compressed parameter count."""
    return validation.integer("uncompressed", uncompressed) / validation.integer(
        "compressed", compressed
    )


def hidden_types_sweep(
    sizes: Sequence[int],
    hidden_types: Sequence[int],
    input_types: int | None = None,
    output_types: int | None = None,
) -> list[float]:
    """Compression ratio of an SGB MLP for each k in ``hidden_types`` (k types in every
    hidden layer, capped at the layer's width), inputs and outputs typed as given."""
    dense = dense_param_count(sizes)
    validation.integers("hidden_types", hidden_types)
    ratios = []
    for k in hidden_types:
        types = [input_types, *(min(k, n) for n in sizes[1:-1]), output_types]
        ratios.append(compression_ratio(dense, sgb_param_count(sizes, types)))
    return ratios
