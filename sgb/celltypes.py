"""Neurons grouped into cell types, and type tables expanded to full weight arrays.

Cell types are contiguous, balanced blocks of neurons. When ``n`` is not a
multiple of ``k`` the first ``n % k`` types get one neuron more.
"""

import functools
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from sgb import validation


def _check_counts(n: int, k: int, n_name: str = "n", k_name: str = "k") -> None:
    validation.integer(n_name, n)
    validation.integer(k_name, k)
    if k > n:
        raise ValueError(f"{k_name}={k} cell types is more than the {n_name}={n} neurons")


def type_sizes(n: int, k: int) -> np.ndarray:
    """Neurons per cell type, shape (k,): balanced, remainder to the first types."""
    _check_counts(n, k)
    sizes = np.full(k, n // k, dtype=np.int64)
    sizes[: n % k] += 1
    return sizes


def assign_cell_types(n: int, k: int) -> np.ndarray:
    """Cell type of each of ``n`` neurons, shape (n,), values in [0, k), non-decreasing."""
    sizes = type_sizes(n, k)  # checks n and k first
    return np.repeat(np.arange(len(sizes)), sizes)


def expand_table(table: jnp.ndarray, shape: Sequence[int]) -> jnp.ndarray:
    """Expand a type table to a full array of the given shape.

    ``table`` has one axis per axis of ``shape`` with ``table.shape[i]`` cell
    types along axis ``i`` (e.g. (k_in, k_out) -> (n_in, n_out), or a 4-D conv
    kernel table (k_h, k_w, k_cin, k_cout) -> (h, w, c_in, c_out)). Entry
    ``[a, b, ...]`` of the result is ``table[type(a), type(b), ...]``.
    """
    if not hasattr(table, "ndim"):
        raise TypeError(f"table must be an array, got {table!r}")
    shape = validation.integers("shape", shape)
    if table.ndim != len(shape):
        raise ValueError(
            f"table has {table.ndim} axes but shape {shape} has {len(shape)}; they must match"
        )
    for axis, (k, n) in enumerate(zip(table.shape, shape, strict=True)):
        _check_counts(n, k, f"shape[{axis}]", f"table.shape[{axis}]")
    return _expand(table, shape)


@functools.partial(jax.jit, static_argnums=1)
def _expand(table: jnp.ndarray, shape: tuple[int, ...]) -> jnp.ndarray:
    out = table
    for axis, n in enumerate(shape):
        out = _repeat_blocks(out, axis, n)
    return out


def _repeat_blocks(x: jnp.ndarray, axis: int, n: int) -> jnp.ndarray:
    """Repeat the k entries of ``x`` along ``axis`` into n balanced contiguous blocks.

    Written as broadcasts of the types of each block size (not a gather), so the
    gradient is a sum over each block rather than a scatter.
    """
    k = x.shape[axis]
    q, r = divmod(n, k)
    parts = []
    for lo, hi, size in ((0, r, q + 1), (r, k, q)):
        if hi == lo:
            continue
        part = jnp.expand_dims(jax.lax.slice_in_dim(x, lo, hi, axis=axis), axis + 1)
        part = jnp.broadcast_to(part, part.shape[: axis + 1] + (size,) + part.shape[axis + 2 :])
        parts.append(part.reshape(x.shape[:axis] + ((hi - lo) * size,) + x.shape[axis + 1 :]))
    return jnp.concatenate(parts, axis=axis)


def sum_blocks(x: jnp.ndarray, types: Sequence[int]) -> jnp.ndarray:
    """The transpose of ``expand_table``: (n_in, n_out, ...) -> ``types``, the sum of each
    type-table entry's block of ``x``."""
    if not hasattr(x, "ndim"):
        raise TypeError(f"x must be an array, got {x!r}")
    types = validation.integers("types", types)
    if len(types) != x.ndim:
        raise ValueError(f"types {types} must have one entry per axis of x {tuple(x.shape)}")
    for axis, (k, n) in enumerate(zip(types, x.shape, strict=True)):
        _check_counts(n, k, f"x.shape[{axis}]", f"types[{axis}]")
    return _sum_blocks(x, tuple(types))


@functools.partial(jax.jit, static_argnums=1)
def _sum_blocks(x: jnp.ndarray, types: tuple[int, ...]) -> jnp.ndarray:
    expand = functools.partial(_expand, shape=x.shape)
    (table,) = jax.linear_transpose(expand, jax.ShapeDtypeStruct(types, x.dtype))(x)
    return table


def block_counts(shape: Sequence[int], types: Sequence[int]) -> np.ndarray:
    """Synapses per type-table entry, shape ``types``: how often each entry is expanded."""
    shape, types = validation.integers("shape", shape), validation.integers("types", types)
    if len(shape) != len(types):
        raise ValueError(f"shape {tuple(shape)} and types {tuple(types)} must have equal length")
    counts = np.ones((), dtype=np.int64)
    for axis, (n, k) in enumerate(zip(shape, types, strict=True)):
        _check_counts(n, k, f"shape[{axis}]", f"types[{axis}]")
        counts = np.multiply.outer(counts, type_sizes(n, k))
    return counts


def type_pair_block(kernel: jnp.ndarray, types: Sequence[int], pair: Sequence[int]) -> jnp.ndarray:
    """The synapses of one type-table entry: the sub-array of ``kernel`` whose neurons have
    the types in ``pair`` along each axis (``types`` = types per axis)."""
    if not hasattr(kernel, "shape"):
        raise TypeError(f"kernel must be an array, got {kernel!r}")
    types = validation.integers("types", types)
    pair = validation.integers("pair", pair, minimum=0)
    if not len(kernel.shape) == len(types) == len(pair):
        raise ValueError(f"kernel {kernel.shape}, types {types} and pair {pair} must match")
    index = []
    for n, k, t in zip(kernel.shape, types, pair, strict=True):
        _check_counts(n, k, "kernel's axis", "types entry")
        if not 0 <= t < k:
            raise ValueError(f"pair entry {t} is not a type in [0, {k})")
        index.append(np.flatnonzero(assign_cell_types(n, k) == t))
    return kernel[np.ix_(*index)]
