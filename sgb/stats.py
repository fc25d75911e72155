"""Summary statistics for seeds and populations: SEM, confidence intervals, Pearson r, paired t."""

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
from scipy import stats as scipy_stats

from sgb import validation


class TestResult(NamedTuple):
    """A statistic, its p-value (two-sided) and the degrees of freedom or sample size."""

    statistic: float
    p_value: float
    dof: int


def sem(values, axis: int = 0) -> np.ndarray:
    """Standard error of the mean along ``axis`` (ddof=1)."""
    values = validation.real_array("values", values)
    axis = validation.integer("axis", axis, minimum=None)
    if not -values.ndim <= axis < values.ndim:
        raise ValueError(f"axis {axis} is out of range for values of shape {values.shape}")
    if values.shape[axis] < 2:
        raise ValueError("the standard error needs at least 2 values along the axis")
    return values.std(axis=axis, ddof=1) / np.sqrt(values.shape[axis])


def mean_ci(values, level: float = 0.95) -> tuple[float, float, float]:
    """Mean and Student-t confidence interval (mean, low, high) of a 1-D sample that varies."""
    level = validation.fraction("level", level)
    values = validation.varying("values", validation.sample("values", values))
    half = scipy_stats.t.ppf(0.5 + level / 2, values.size - 1) * sem(values)
    mean = float(values.mean())
    return mean, mean - float(half), mean + float(half)


def _pair(names: tuple[str, str], x, y) -> tuple[np.ndarray, np.ndarray]:
    """Two samples of the same length."""
    x, y = validation.sample(names[0], x), validation.sample(names[1], y)
    if x.shape != y.shape:
        raise ValueError(
            f"{' and '.join(names)} must have the same length, got {x.size} and {y.size}"
        )
    return x, y


def pearson(x, y) -> TestResult:
    """Pearson's r between two equal-length samples, with its two-sided p-value."""
    x, y = _pair(("x", "y"), x, y)
    validation.varying("x", x), validation.varying("y", y)
    result = scipy_stats.pearsonr(x, y)
    return TestResult(float(result.statistic), float(result.pvalue), x.size - 2)


def paired_t(a, b) -> TestResult:
    """Paired t-test of a - b against zero; dof = n - 1."""
    a, b = _pair(("a", "b"), a, b)
    validation.varying("a - b", a - b)
    result = scipy_stats.ttest_rel(a, b)
    return TestResult(float(result.statistic), float(result.pvalue), a.size - 1)


def one_sample_t(values, reference: float) -> TestResult:
    """One-sample t-test of the mean of ``values`` against a fixed ``reference``; dof = n - 1."""
    values = validation.varying("values", validation.sample("values", values))
    reference = validation.real("reference", reference)
    result = scipy_stats.ttest_1samp(values, reference)
    return TestResult(float(result.statistic), float(result.pvalue), values.size - 1)


def _log_curve(side: str, x, y) -> tuple[np.ndarray, np.ndarray]:
    """Curve ``side``'s log(x) and y: x positive and strictly increasing, y as long."""
    x, y = _pair((f"x_{side}", f"y_{side}"), x, y)
    if x.min() <= 0:
        raise ValueError(f"x_{side} must be positive (curves meet in log x), got {x.min():g}")
    if np.any(np.diff(x) <= 0):
        raise ValueError(f"x_{side} must be strictly increasing, got {x.tolist()}")
    return np.log(x), y


def crossings(x_a, y_a, x_b, y_b) -> list[float]:
    """Where curve a minus curve b changes sign, in x, low to high.

    Each curve is given at its own positive x (for example compression ratios), at least
    two, strictly ascending; the ranges of x must overlap. Both curves are interpolated
    linearly in log(x) on the union of their points, within the range both cover, and
    each sign change is located by linear interpolation of the difference there."""
    (xa, ya), (xb, yb) = _log_curve("a", x_a, y_a), _log_curve("b", x_b, y_b)
    low, high = max(xa[0], xb[0]), min(xa[-1], xb[-1])
    if not low < high:
        spans = (
            f"[{np.exp(xa[0]):g}, {np.exp(xa[-1]):g}] and [{np.exp(xb[0]):g}, {np.exp(xb[-1]):g}]"
        )
        raise ValueError(f"x_a and x_b must overlap, got the ranges {spans}")
    grid = np.unique(np.concatenate([xa, xb]))
    grid = grid[(grid >= low) & (grid <= high)]
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


def _mean_curve(name: str, curve: Mapping) -> tuple[np.ndarray, ...]:
    """A curve's x (ascending), and at each its seeds' mean, SEM and degrees of freedom."""
    validation.instance(name, curve, Mapping)
    if len(curve) < 2:
        raise ValueError(f"{name} must hold at least 2 points, got {len(curve)}")
    xs = sorted(validation.positive(f"{name}'s x", x) for x in curve)
    values = [validation.sample(f"{name}[{x!r}]", curve[x]) for x in xs]
    return (
        np.array(xs),
        np.array([v.mean() for v in values]),
        np.array([sem(v) for v in values]),
        np.array([v.size - 1 for v in values]),
    )


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
    draws = validation.integer("draws", draws)
    level = validation.fraction("level", level)
    rng = np.random.default_rng(validation.seed("seed", seed))
    (xa, ma, sa, da), (xb, mb, sb, db) = _mean_curve("a", a), _mean_curve("b", b)
    first = crossings(xa, ma, xb, mb)
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
