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


def crossings(x_a, y_a, x_b, y_b) -> list[float]:
    """Where curve a minus curve b changes sign, in x, low to high.

    Each curve is given at its own positive x (for example compression ratios), sorted
    ascending; both are interpolated linearly in log(x) on the union of their points,
    within the range both cover, and each sign change is located by linear
    interpolation of the difference there."""
    xa, ya, xb, yb = (
        _as_array(name, v) for name, v in (("x_a", x_a), ("y_a", y_a), ("x_b", x_b), ("y_b", y_b))
    )
    if not (xa.ndim == xb.ndim == 1 and xa.shape == ya.shape and xb.shape == yb.shape):
        raise ValueError("each curve must be two 1-D sequences of the same length, x and y")
    xa, xb = np.log(xa), np.log(xb)
    grid = np.unique(np.concatenate([xa, xb]))
    grid = grid[(grid >= max(xa.min(), xb.min())) & (grid <= min(xa.max(), xb.max()))]
    diff = np.interp(grid, xa, ya) - np.interp(grid, xb, yb)
    points = []
    for i in np.nonzero(np.sign(diff[:-1]) * np.sign(diff[1:]) < 0)[0]:
        t = diff[i] / (diff[i] - diff[i + 1])
        points.append(float(np.exp(grid[i] + t * (grid[i + 1] - grid[i]))))
    return points


class CrossingInterval(NamedTuple):
    """The first crossing of two mean curves (``nan`` if they do not cross), the 95 %
    interval (low, high) of the first crossing over the simulated curves that cross, the
    share of simulated curves that cross, and the number simulated."""

    estimate: float
    low: float
    high: float
    share_crossing: float
    draws: int


def bootstrap_crossing(
    a: dict[float, np.ndarray],
    b: dict[float, np.ndarray],
    draws: int = 2000,
    level: float = 0.95,
    seed: int = 0,
) -> CrossingInterval:
    """The first crossing of the mean curves of ``a`` and ``b`` (``crossings``), with a
    parametric bootstrap interval.

    ``a`` and ``b`` map x (a compression ratio) to the values of the seeds run there, at
    least two per point. Each simulated curve draws every point's mean from its Student-t
    sampling distribution (the seeds' mean, their SEM, n - 1 degrees of freedom), point by
    point and independently. Resampling the seeds instead undercovers at the few seeds
    sweeps have: on curves with a known crossing it covered it in 77 % of 150 trials at 3
    seeds and 87 % at 5, the t draws in 99 % and 97 % (the curves of ``tests/test_verdicts``)."""
    validation.integer("draws", draws)
    if not 0.0 < validation.real("level", level) < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    curves = []
    for name, curve in (("a", a), ("b", b)):
        xs = sorted(curve)
        values = [_as_1d(f"{name}[{x}]", curve[x]) for x in xs]
        mean = np.array([v.mean() for v in values])
        spread = np.array([sem(v) for v in values])
        dof = np.array([v.size - 1 for v in values])
        curves.append((np.array(xs), mean, spread, dof))
    (xa, ma, sa, da), (xb, mb, sb, db) = curves
    first = crossings(xa, ma, xb, mb)
    rng = np.random.default_rng(seed)
    found = []
    for _ in range(draws):
        ya = ma + sa * rng.standard_t(da)
        yb = mb + sb * rng.standard_t(db)
        points = crossings(xa, ya, xb, yb)
        if points:
            found.append(points[0])
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(found, [tail, 100 - tail]) if found else (np.nan, np.nan)
    estimate = first[0] if first else np.nan
    return CrossingInterval(float(estimate), float(low), float(high), len(found) / draws, draws)
