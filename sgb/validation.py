"""Checks of public arguments: each raises ``TypeError`` or ``ValueError`` naming the argument.

Configs and constructors call these at the door, so a bad setting fails before any
work starts, with a message that says which argument is wrong and why.
"""

import math
import numbers
import os
from collections.abc import Collection, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np


def integer(name: str, value: Any, minimum: int | None = 1) -> int:
    """``value`` as an int; booleans and non-integral numbers are a ``TypeError``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer, got {value!r}")
    if minimum is not None and value < minimum:
        bound = "a positive integer" if minimum == 1 else f">= {minimum}"
        raise ValueError(f"{name} must be {bound}, got {value!r}")
    return int(value)


def integers(name: str, values: Any, minimum: int = 1, *, allow_none: bool = False) -> tuple:
    """A non-empty sequence of integers >= ``minimum`` (``None`` entries if ``allow_none``)."""
    if isinstance(values, str | bytes) or not isinstance(values, Sequence):
        raise TypeError(f"{name} must be a sequence of integers, got {values!r}")
    if len(values) == 0:
        raise ValueError(f"{name} must not be empty")
    return tuple(
        None if (v is None and allow_none) else integer(f"{name}[{i}]", v, minimum)
        for i, v in enumerate(values)
    )


def distinct(name: str, values: Sequence[Any]) -> tuple:
    """``values`` as a tuple if no entry repeats; else a ``ValueError`` naming the repeats."""
    values = tuple(values)
    repeated = sorted({repr(v) for i, v in enumerate(values) if v in values[:i]})
    if repeated:
        repeats = ", ".join(repeated)
        raise ValueError(f"{name} must not repeat an entry, got {values!r} ({repeats} repeated)")
    return values


def real(name: str, value: Any) -> float:
    """``value`` as a finite float: a non-number is a ``TypeError``, nan or inf a ``ValueError``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return float(value)


def reals(name: str, values: Any) -> tuple[float, ...]:
    """A non-empty sequence of finite real numbers, as a tuple of floats."""
    if isinstance(values, str | bytes) or not isinstance(values, Sequence):
        raise TypeError(f"{name} must be a sequence of real numbers, got {values!r}")
    if len(values) == 0:
        raise ValueError(f"{name} must not be empty")
    return tuple(real(f"{name}[{i}]", v) for i, v in enumerate(values))


def positive(name: str, value: Any) -> float:
    """A finite real number > 0."""
    value = real(name, value)
    if value <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return value


def non_negative(name: str, value: Any) -> float:
    """A finite real number >= 0."""
    value = real(name, value)
    if value < 0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return value


def in_range(name: str, value: Any, low: float, high: float, *, low_open: bool = False) -> float:
    """A finite real number in [low, high], or (low, high] when ``low_open``."""
    value = real(name, value)
    if value > high or value < low or (low_open and value == low):
        interval = f"{'(' if low_open else '['}{low}, {high}]"
        raise ValueError(f"{name} must lie in {interval}, got {value!r}")
    return value


def fraction(name: str, value: Any) -> float:
    """A finite real number strictly between 0 and 1 (a confidence level, a target)."""
    value = real(name, value)
    if not 0 < value < 1:
        raise ValueError(f"{name} must lie in (0, 1), got {value!r}")
    return value


def choice(name: str, value: Any, options: Collection[Any]) -> Any:
    """One of ``options``."""
    if not isinstance(value, str | int | type(None)) or value not in options:
        raise ValueError(f"{name} must be one of {tuple(options)}, got {value!r}")
    return value


def instance(name: str, value: Any, types: type | tuple[type, ...]) -> Any:
    """An instance of ``types``."""
    if not isinstance(value, types):
        options = types if isinstance(types, tuple) else (types,)
        expected = " or ".join(t.__name__ for t in options)
        raise TypeError(f"{name} must be a {expected}, got {value!r}")
    return value


def path(name: str, value: Any) -> str | os.PathLike:
    """A file system path: a non-empty ``str`` or an ``os.PathLike`` (``pathlib.Path``)."""
    if not isinstance(value, str | os.PathLike):
        raise TypeError(f"{name} must be a path (str or os.PathLike), got {value!r}")
    if not os.fspath(value):
        raise ValueError(f"{name} must not be empty")
    return value


def seed(name: str, value: Any) -> int:
    """A seed: an integer in [0, 2**32), the range every generator the package seeds takes."""
    value = integer(name, value, minimum=0)
    if value >= 2**32:
        raise ValueError(f"{name} must be < 2**32, got {value!r}")
    return value


def is_traced(value: Any) -> bool:
    """Whether ``value`` is a jax tracer (inside ``jit``, ``vmap`` or ``grad``): its shape
    and dtype are known, its values are not, so only they can be checked."""
    return isinstance(value, jax.core.Tracer)


def array(name: str, value: Any, *, ndim: int | None = None, min_ndim: int = 0) -> Any:
    """An array-like with a shape and a numeric dtype (a tracer is accepted as it is);
    ``ndim``/``min_ndim`` bound its number of axes."""
    if isinstance(value, str | bytes) or value is None:
        raise TypeError(f"{name} must be an array, got {value!r}")
    if not hasattr(value, "shape"):
        try:
            value = np.asarray(value)
        except (TypeError, ValueError) as error:
            raise TypeError(f"{name} must be an array, got {value!r}") from error
    if _is_key_dtype(value) or not jnp.issubdtype(value.dtype, jnp.number):
        raise TypeError(f"{name} must hold numbers, got dtype {value.dtype}")
    if ndim is not None and len(value.shape) != ndim:
        raise ValueError(f"{name} must have {ndim} axes, got shape {tuple(value.shape)}")
    if len(value.shape) < min_ndim:
        raise ValueError(f"{name} needs at least {min_ndim} axes, got shape {tuple(value.shape)}")
    return value


def _is_key_dtype(value: Any) -> bool:
    return jax.dtypes.issubdtype(getattr(value, "dtype", None), jax.dtypes.prng_key)


def _all_finite(values: Any) -> bool:
    """Whether every entry of a concrete float array is finite, in one pass and without a
    boolean copy: the float64 sum of finite float32 values cannot overflow, so a
    non-finite sum means a nan or inf (only then, or for float64 data, is it looked for)."""
    values = np.asarray(values)
    if values.dtype.kind != "f" or values.size == 0:
        return True
    if np.isfinite(np.sum(values, dtype=np.float64)):
        return True
    return bool(np.isfinite(values).all())


def finite_array(name: str, value: Any, *, allow_empty: bool = False, **shape: int) -> Any:
    """``array`` whose entries are all finite and, unless ``allow_empty``, not none; a tracer
    is checked only for its shape."""
    value = array(name, value, **shape)
    if not allow_empty and 0 in tuple(value.shape):
        raise ValueError(f"{name} is empty (shape {tuple(value.shape)})")
    if not is_traced(value) and not _all_finite(value):
        raise ValueError(f"{name} holds nan or inf values")
    return value


def real_array(name: str, value: Any, **shape: int) -> np.ndarray:
    """``finite_array`` of real numbers, as a float64 numpy array (no tracers: statistics
    of concrete values)."""
    value = np.asarray(finite_array(name, value, **shape))
    if value.dtype.kind == "c":
        raise TypeError(f"{name} must hold real numbers, got dtype {value.dtype}")
    return value.astype(np.float64)


def sample(name: str, value: Any, minimum: int = 2) -> np.ndarray:
    """A 1-D sample of at least ``minimum`` finite real numbers, as a float64 array."""
    value = real_array(name, value, ndim=1)
    if value.size < minimum:
        raise ValueError(f"{name} needs at least {minimum} values, got {value.size}")
    return value


def varying(name: str, value: np.ndarray) -> np.ndarray:
    """``value`` unless all its entries are equal: a constant sample has no spread."""
    if np.all(value == value.flat[0]):
        raise ValueError(f"{name} is constant, so the statistic is undefined")
    return value


def labels(name: str, value: Any, num_classes: int | None = None) -> Any:
    """Integer class labels, in [0, ``num_classes``) when it is given (a tracer is checked
    only for its dtype)."""
    value = array(name, value)
    if not jnp.issubdtype(value.dtype, jnp.integer):
        raise TypeError(f"{name} must be integer class labels, got dtype {value.dtype}")
    if is_traced(value) or np.size(value) == 0:
        return value
    values = np.asarray(value)
    low, high = int(values.min()), int(values.max())
    if low < 0 or (num_classes is not None and high >= num_classes):
        bound = f"lie in [0, {num_classes})" if num_classes is not None else "be >= 0"
        raise ValueError(f"{name} must {bound}, got labels from {low} to {high}")
    return value


def prng_key(name: str, value: Any) -> Any:
    """A jax PRNG key: a typed key array or raw uint32 key data of shape (..., 2)."""
    if _is_key_dtype(value):
        return value
    shape = getattr(value, "shape", None)
    if shape is None or np.dtype(value.dtype) != np.uint32 or not shape or shape[-1] != 2:
        raise TypeError(f"{name} must be a jax PRNG key (jax.random.key), got {value!r}")
    return value


def shape_differences(
    tree: Any, expected: Any, limit: int = 4
) -> list[tuple[str, tuple[int, ...] | None, tuple[int, ...] | None]]:
    """The first ``limit`` leaves, by path, whose shapes differ between the pytree ``tree``
    and ``expected`` (arrays or ``jax.ShapeDtypeStruct``, e.g. from ``jax.eval_shape``):
    (leaf path, its shape in ``tree``, in ``expected``), ``None`` where a side lacks it."""

    def shapes(t: Any) -> dict[str, tuple[int, ...]]:
        leaves = jax.tree_util.tree_leaves_with_path(t)
        return {jax.tree_util.keystr(k): tuple(np.shape(v)) for k, v in leaves}

    got, want = shapes(tree), shapes(expected)
    differing = sorted(k for k in got.keys() | want.keys() if got.get(k) != want.get(k))
    return [(k, got.get(k), want.get(k)) for k in differing[:limit]]


def finite_tree(name: str, tree: Any) -> Any:
    """A pytree whose concrete float leaves are all finite; the error names the first leaf
    holding a nan or inf."""
    for path, leaf in jax.tree_util.tree_leaves_with_path(tree):
        if not is_traced(leaf) and not _all_finite(leaf):
            raise ValueError(f"{name}{jax.tree_util.keystr(path)} holds nan or inf values")
    return tree


class CorruptFile(ValueError):
    """A file the package reads is damaged, cut short or not what it should be.

    The message names the file (``what`` it is, e.g. "checkpoint", then its path), what
    is wrong with it (``problem``, e.g. "is unreadable (...)") and what to do
    (``remedy``). A ``ValueError``, so callers that report bad input (the command line
    among them) report it too.
    """

    def __init__(self, path: Any, problem: str, remedy: str, what: str = "file") -> None:
        self.path, self.problem, self.remedy = path, problem, remedy
        super().__init__(f"{what} {path} {problem}; {remedy}")


RESTART = "delete it and run again to start this run afresh"
REDOWNLOAD = "delete it and run again to download it anew"
RETRAIN = "delete it and its sidecar (.json) and run again to train it anew"
