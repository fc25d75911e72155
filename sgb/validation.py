"""Checks of public arguments: each raises ``TypeError`` or ``ValueError`` naming the argument.

Configs and constructors call these at the door, so a bad setting fails before any
work starts, with a message that says which argument is wrong and why.
"""

import math
import numbers
from collections.abc import Collection, Sequence
from typing import Any


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


def real(name: str, value: Any) -> float:
    """``value`` as a finite float: a non-number is a ``TypeError``, nan or inf a ``ValueError``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return float(value)


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
