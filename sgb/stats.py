"""Summary statistics for seeds and populations: SEM, confidence intervals, Pearson r, paired t."""

from typing import NamedTuple

import numpy as np
from scipy import stats as scipy_stats

from sgb import validation


class TestResult(NamedTuple):
    """A statistic, its p-value (two-sided) and the degrees of freedom or sample size."""

    statistic: float
    p_value: float
    dof: int


def _as_array(name: str, values) -> np.ndarray:
    """``values`` as a float64 array of finite numbers."""
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise TypeError(f"{name} must be numbers, got {values!r}") from error
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {values!r}")
    return array


def _as_1d(name: str, values) -> np.ndarray:
    array = _as_array(name, values)
    if array.ndim != 1 or array.size < 2:
        raise ValueError(f"{name} must be a 1-D sequence of at least 2 values, got {array.shape}")
    return array


def _not_constant(name: str, values: np.ndarray) -> np.ndarray:
    if np.all(values == values[0]):
        raise ValueError(f"{name} is constant, so the statistic is undefined")
    return values


def sem(values, axis: int = 0) -> np.ndarray:
    """Standard error of the mean along ``axis`` (ddof=1)."""
    values = _as_array("values", values)
    axis = validation.integer("axis", axis, minimum=None)
    if not -values.ndim <= axis < values.ndim:
        raise ValueError(f"axis {axis} is out of range for values of shape {values.shape}")
    if values.shape[axis] < 2:
        raise ValueError("the standard error needs at least 2 values along the axis")
    return values.std(axis=axis, ddof=1) / np.sqrt(values.shape[axis])


def mean_ci(values, level: float = 0.95) -> tuple[float, float, float]:
    """Mean and Student-t confidence interval (mean, low, high) of a 1-D sample."""
    if not 0.0 < validation.real("level", level) < 1.0:
        raise ValueError(f"level must lie in (0, 1), got {level}")
    values = _as_1d("values", values)
    half = scipy_stats.t.ppf(0.5 + level / 2, values.size - 1) * sem(values)
    mean = float(values.mean())
    return mean, mean - float(half), mean + float(half)


def pearson(x, y) -> TestResult:
    """Pearson's r between two equal-length samples, with its two-sided p-value."""
    x, y = _as_1d("x", x), _as_1d("y", y)
    if x.shape != y.shape:
        raise ValueError(f"x and y must have the same length, got {x.size} and {y.size}")
    _not_constant("x", x), _not_constant("y", y)
    result = scipy_stats.pearsonr(x, y)
    return TestResult(float(result.statistic), float(result.pvalue), x.size - 2)


def paired_t(a, b) -> TestResult:
    """Paired t-test of a - b against zero; dof = n - 1."""
    a, b = _as_1d("a", a), _as_1d("b", b)
    if a.shape != b.shape:
        raise ValueError(f"a and b must have the same length, got {a.size} and {b.size}")
    _not_constant("a - b", a - b)
    result = scipy_stats.ttest_rel(a, b)
    return TestResult(float(result.statistic), float(result.pvalue), a.size - 1)


def one_sample_t(values, reference: float) -> TestResult:
    """One-sample t-test of the mean of ``values`` against a fixed ``reference``; dof = n - 1."""
    values = _not_constant("values", _as_1d("values", values))
    validation.real("reference", reference)
    result = scipy_stats.ttest_1samp(values, reference)
    return TestResult(float(result.statistic), float(result.pvalue), values.size - 1)
