"""Parameter counts and compression ratios, one definition for every model.

compression ratio = parameters of the uncompressed network
                    / parameters that define the compressed one,

under one of two conventions (``compression``):

* ``"ours"``: every parameter that defines a network. The uncompressed network
  counts weights and biases; the SGB its means, rhos and per-neuron biases; the
  DGB all its g-nets' parameters and the p-net's biases that are stored directly
  (as the authors' DGB code counts, ``GNetList.compression``).
* ``"authors"`` (their SGB code): weights only against the mean tables only (SGB)
  or the kernels' g-nets only (DGB).

A DGB's g-nets are laid out by ``sgb.dgb_layout`` (``"ours"`` or ``"authors"``); its
``setting`` is the width of the first hidden layer of its kernels' g-nets.
"""

from collections.abc import Sequence
from typing import Any, Literal

import jax
import numpy as np

from sgb import validation
from sgb.dgb_layout import code_dims, gnet_specs, input_dim, stored_bias_layers

ModelKind = Literal["sgb", "dgb", "dense"]
MODEL_KINDS: tuple[str, ...] = ("sgb", "dgb", "dense")
Convention = Literal["ours", "authors"]
CONVENTIONS: tuple[str, ...] = ("ours", "authors")


def _check_sizes(sizes: Sequence[int]) -> None:
    if len(validation.integers("sizes", sizes)) < 2:
        raise ValueError(f"sizes needs at least an input and an output layer, got {sizes}")


def weight_count(sizes: Sequence[int]) -> int:
    """Weights (no biases) of a plain MLP with layer sizes e.g. (784, 800, 10)."""
    _check_sizes(sizes)
    return int(sum(a * b for a, b in zip(sizes[:-1], sizes[1:], strict=True)))


def dense_param_count(sizes: Sequence[int]) -> int:
    """Weights and biases of a plain MLP with layer sizes e.g. (784, 800, 10)."""
    return weight_count(sizes) + int(sum(sizes[1:]))


def _types(sizes: Sequence[int], cell_types: Sequence[int | None]) -> list[int]:
    _check_sizes(sizes)
    if len(validation.integers("cell_types", cell_types, allow_none=True)) != len(sizes):
        raise ValueError(f"cell_types {cell_types} must have one entry per layer of {sizes}")
    types = [n if k is None else k for n, k in zip(sizes, cell_types, strict=True)]
    for n, k in zip(sizes, types, strict=True):
        if not 0 < k <= n:
            raise ValueError(f"cell types must lie in [1, {n}] for a layer of {n}, got {k}")
    return types


def sgb_table_count(sizes: Sequence[int], cell_types: Sequence[int | None]) -> int:
    """Entries of an SGB MLP's mean tables (one per type pair and layer)."""
    types = _types(sizes, cell_types)
    return int(sum(a * b for a, b in zip(types[:-1], types[1:], strict=True)))


def sgb_param_count(sizes: Sequence[int], cell_types: Sequence[int | None]) -> int:
    """Means, rhos and biases of an SGB MLP; ``cell_types`` as in ``SGBMLP``."""
    return 2 * sgb_table_count(sizes, cell_types) + int(sum(sizes[1:]))


def gnet_param_count(code_dim: int, hidden: Sequence[int]) -> int:
    """Parameters of one g-net with ``code_dim`` inputs, ``hidden`` layers and one output."""
    validation.integers("gnet hidden widths", hidden)
    return dense_param_count((code_dim, *hidden, 1))


def dgb_gnet_count(
    sizes: Sequence[int], width: int, layout: str = "ours", kernels_only: bool = False
) -> int:
    """Parameters of the g-nets (``kernels_only``: those of the kernels) of a DGB MLP with
    layer ``sizes``, kernels' g-nets of first hidden ``width``, laid out by ``layout``."""
    _check_sizes(sizes)
    dims = code_dims(sizes)
    specs = gnet_specs(sizes, width, layout)
    return int(
        sum(
            gnet_param_count(input_dim(s, dims), s.hidden)
            for s in specs
            if s.target == "kernel" or not kernels_only
        )
    )


def dgb_param_count(sizes: Sequence[int], width: int, layout: str = "ours") -> int:
    """Genome size of a DGB MLP: all its g-nets plus the p-net's biases stored directly."""
    stored = stored_bias_layers(sizes, gnet_specs(sizes, width, layout))
    return dgb_gnet_count(sizes, width, layout) + int(sum(sizes[i + 1] for i in stored))


def tree_param_count(params: Any) -> int:
    """Number of scalars in a parameter pytree."""
    return int(sum(np.size(leaf) for leaf in jax.tree_util.tree_leaves(params)))


def compression_ratio(uncompressed: int, compressed: int) -> float:
    """Uncompressed over compressed parameter count."""
    return validation.integer("uncompressed", uncompressed) / validation.integer(
        "compressed", compressed
    )


def genome_size(
    kind: ModelKind,
    sizes: Sequence[int],
    setting: int,
    in_types: int,
    out_types: int,
    convention: Convention = "ours",
    layout: str = "ours",
) -> int:
    """Parameters counted for a model of the dense stack ``sizes`` under ``convention``.

    ``setting``: cell types of every hidden layer (``"sgb"``) or the width of the
    kernels' g-nets' first hidden layer (``"dgb"``, laid out by ``layout``); ignored for
    ``"dense"``.
    """
    ours = validation.choice("convention", convention, CONVENTIONS) == "ours"
    if kind == "sgb":
        types = (in_types, *([setting] * (len(sizes) - 2)), out_types)
        return sgb_param_count(sizes, types) if ours else sgb_table_count(sizes, types)
    if kind == "dgb":
        if ours:
            return dgb_param_count(sizes, setting, layout)
        return dgb_gnet_count(sizes, setting, layout, kernels_only=True)
    if kind == "dense":
        return dense_param_count(sizes) if ours else weight_count(sizes)
    raise ValueError(f"kind must be one of {MODEL_KINDS}, got {kind!r}")


def compression(
    kind: ModelKind,
    sizes: Sequence[int],
    setting: int,
    in_types: int,
    out_types: int,
    convention: Convention = "ours",
    layout: str = "ours",
) -> float:
    """Compression ratio of any model kind under ``convention`` ("ours" or "authors"); a
    DGB's g-nets laid out by ``layout``."""
    uncompressed = genome_size("dense", sizes, 0, in_types, out_types, convention)
    compressed = genome_size(kind, sizes, setting, in_types, out_types, convention, layout)
    return compression_ratio(uncompressed, compressed)


def setting_for_ratio(
    kind: ModelKind,
    sizes: Sequence[int],
    ratio: float,
    in_types: int,
    out_types: int,
    convention: Convention = "ours",
    layout: str = "ours",
) -> int:
    """The setting (hidden cell types, or g-net width) whose compression is nearest ``ratio``
    on a log scale. SGB types range over 1..min(hidden); g-net widths over 1..4096."""
    if ratio <= 0:
        raise ValueError(f"ratio must be positive, got {ratio}")
    if kind == "sgb":
        candidates = np.arange(1, min(sizes[1:-1]) + 1)
    elif kind == "dgb":
        candidates = np.arange(1, 4097)
    else:
        raise ValueError(f"kind must be 'sgb' or 'dgb', got {kind!r}")
    ratios = np.array(
        [
            compression(kind, sizes, int(c), in_types, out_types, convention, layout)
            for c in candidates
        ]
    )
    return int(candidates[np.argmin(np.abs(np.log(ratios) - np.log(ratio)))])


def authors_nominal_width(sizes: Sequence[int], ratio: float) -> int:
    """The g-net width the authors' DGB script builds for a nominal compression ``ratio``:
    round((p - 20 r) / (60 r)), p the p-net's parameters (``003_MNIST_automatic_2.py``).
    The network it builds is compressed otherwise (``compression(..., layout="authors")``)."""
    p = dense_param_count(sizes)
    return int(np.round((p - 20 * validation.positive("ratio", ratio)) / (60 * ratio)))


def nominal_ratio_table(sizes: Sequence[int], nominal: Sequence[float]) -> list[dict]:
    """For each of the authors' nominal DGB ratios: the width their script builds
    (``authors_nominal_width``) and that network's compression under both conventions,
    laid out as theirs is."""
    rows = []
    for ratio in nominal:
        width = authors_nominal_width(sizes, ratio)
        real = {c: compression("dgb", sizes, width, 1, 1, c, "authors") for c in CONVENTIONS}
        rows.append({"nominal": ratio, "gnet_width": width, **real})
    return rows


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
