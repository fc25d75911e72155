"""The statistics of the book, in one place: tests with their 95 % intervals and power
(one type, ``Test``), the SEM and intervals of seeds and populations, Holm's correction,
crossings of two curves, and pooling over genomes.

Every test estimates an *effect* (a difference of means, or a correlation), with a
two-sided 95 % confidence interval and the *detectable effect*: the smallest true effect
that the test would find (p < 0.05, two-sided) with 80 % power at this sample size. The
rule that turns a test into a verdict is ``sgb.verdicts``.
"""

import math
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
from scipy import stats as scipy_stats

from sgb import validation

LEVEL = 0.95
POWER = 0.8


class _Fields(NamedTuple):  # Test's fields, checked by Test
    name: str
    estimate: float
    low: float
    high: float
    dof: float
    p: float
    detectable: float
    n: int
    statistic: float = math.nan


class Test(_Fields):
    """One test: its name, the effect estimated, its 95 % interval (low, high), degrees of
    freedom (``inf`` for a normal approximation), two-sided p against the null, the
    effect detectable at 80 % power, and the sample size ``n`` per group.

    The estimate and the interval must be finite, with low <= high; dof, p and the
    detectable effect may be ``nan`` where the test has none (a bootstrap interval), else
    dof > 0, p in [0, 1] and detectable > 0."""

    __slots__ = ()

    def __new__(cls, *args, **kwargs) -> "Test":
        t = _Fields(*args, **kwargs)
        low, high = validation.real("low", t.low), validation.real("high", t.high)
        if low > high:
            raise ValueError(f"low must be <= high, got the interval ({low!r}, {high!r})")
        return super().__new__(
            cls,
            validation.instance("name", t.name, str),
            validation.real("estimate", t.estimate),
            low,
            high,
            _unless_nan(_dof, "dof", t.dof),
            _unless_nan(validation.in_range, "p", t.p, 0.0, 1.0),
            _unless_nan(validation.positive, "detectable", t.detectable),
            validation.integer("n", t.n),
            _unless_nan(validation.real, "statistic", t.statistic),
        )

    @classmethod
    def _make(cls, iterable) -> "Test":
        return cls(*iterable)


def _unless_nan(check, name: str, value, *args) -> float:
    """``check(name, value, *args)``, or nan where ``value`` is nan (none for this test)."""
    if isinstance(value, float | np.floating) and math.isnan(value):
        return math.nan
    return check(name, value, *args)


def _dof(name: str, value) -> float:
    """Degrees of freedom as given (an int stays one): a real number > 0, or ``inf``."""
    if value != math.inf:
        validation.positive(name, value)
    return value


def _t_test(name: str, estimate: float, se: float, dof: float, n: int, null: float) -> Test:
    """A t (or, for ``dof=inf``, z) test of ``estimate`` with standard error ``se``."""
    se = validation.positive("the standard error", se)
    dist = scipy_stats.norm if math.isinf(dof) else scipy_stats.t(dof)
    half = dist.ppf(0.5 + LEVEL / 2) * se
    detectable = (dist.ppf(0.5 + LEVEL / 2) + dist.ppf(POWER)) * se
    statistic = (estimate - null) / se
    p = 2 * dist.sf(abs(statistic))
    low, high = estimate - half, estimate + half
    return Test(name, estimate, low, high, dof, float(p), detectable, n, float(statistic))


def welch(a, b) -> Test:
    """Welch's t for mean(a) - mean(b) of two independent samples (Welch-Satterthwaite
    degrees of freedom), not both constant; ``n`` is the smaller sample's size."""
    a, b = validation.sample("a", a), validation.sample("b", b)
    if np.ptp(a) == 0 and np.ptp(b) == 0:
        raise ValueError("a and b are both constant, so the statistic is undefined")
    return contrast([a, b], [1.0, -1.0])._replace(name="Welch t")


def contrast(samples: Sequence, weights: Sequence[float]) -> Test:
    """The linear contrast sum_i w_i mean(sample_i) of independent samples (each of 2 or
    more values, not all constant), its standard error sqrt(sum_i w_i^2 var_i / n_i) and
    Welch-Satterthwaite degrees of freedom; ``welch(a, b)`` is the contrast (1, -1). ``n``
    is the smallest sample's size."""
    if len(samples) != len(weights) or len(samples) < 2:
        raise ValueError(f"need one weight per sample, 2 or more: {len(samples)}, {len(weights)}")
    xs = [validation.sample(f"sample {i}", x) for i, x in enumerate(samples)]
    w = [validation.real(f"weight {i}", v) for i, v in enumerate(weights)]
    if all(np.ptp(x) == 0 for x in xs):
        raise ValueError("every sample is constant, so the statistic is undefined")
    terms = [wi**2 * x.var(ddof=1) / x.size for wi, x in zip(w, xs, strict=True)]
    dof = sum(terms) ** 2 / sum(t**2 / (x.size - 1) for t, x in zip(terms, xs, strict=True))
    estimate = sum(wi * x.mean() for wi, x in zip(w, xs, strict=True))
    return _t_test("contrast t", estimate, math.sqrt(sum(terms)), dof, min(x.size for x in xs), 0)


def paired(a, b) -> Test:
    """Paired t for mean(a - b) (same units measured twice, a - b not constant); dof = n - 1."""
    a, b = validation.sample("a", a), validation.sample("b", b)
    if a.shape != b.shape:
        raise ValueError(f"a and b must have the same length, got {a.size} and {b.size}")
    d = validation.varying("a - b", a - b)
    return _t_test("paired t", d.mean(), d.std(ddof=1) / math.sqrt(d.size), d.size - 1, d.size, 0)


def one_sample(values, null: float) -> Test:
    """One-sample t of mean(values) (not constant) against a fixed ``null``; dof = n - 1."""
    v = validation.varying("values", validation.sample("values", values))
    null = validation.real("null", null)
    se = v.std(ddof=1) / math.sqrt(v.size)
    return _t_test("one-sample t", v.mean(), se, v.size - 1, v.size, null)


def slope(x, y) -> Test:
    """The least-squares slope of ``y`` on ``x`` (the same length, ``x`` not constant), its
    t test against 0 with n - 2 degrees of freedom (independent errors of one variance)."""
    x = validation.varying("x", validation.sample("x", x))
    y = validation.sample("y", y)
    if x.size != y.size or x.size < 3:
        raise ValueError(f"x and y need the same length, at least 3, got {x.size} and {y.size}")
    dx = x - x.mean()
    b = float(dx @ (y - y.mean()) / (dx @ dx))
    residual = y - y.mean() - b * dx
    se = math.sqrt(float(residual @ residual) / (x.size - 2) / float(dx @ dx))
    return _t_test("least-squares slope t", b, se, x.size - 2, x.size, 0.0)


def estimate_test(name: str, estimate: float, stderr: float, n: int) -> Test:
    """A z test of a Monte Carlo estimate with its standard error (normal approximation)."""
    estimate, stderr = validation.real("estimate", estimate), validation.positive("stderr", stderr)
    return _t_test(validation.instance("name", name, str), estimate, stderr, math.inf, n, 0)


def fisher_r(x, y) -> Test:
    """Pearson's r of two samples of the same length, at least 4, neither constant nor
    the one a linear function of the other; ``fisher_from_r``."""
    x, y = validation.sample("x", x, minimum=4), validation.sample("y", y, minimum=4)
    if x.shape != y.shape:
        raise ValueError(f"x and y must have the same length, got {x.size} and {y.size}")
    validation.varying("x", x), validation.varying("y", y)
    r = float(np.corrcoef(x, y)[0, 1])
    if abs(r) == 1:
        raise ValueError(f"x and y are perfectly correlated (r = {r}): Fisher's z is infinite")
    return _fisher(r, x.size)


def fisher_from_r(r: float, n: int) -> Test:
    """Pearson's r of ``n`` >= 4 pairs, -1 < r < 1, with its Fisher-z interval; detectable:
    the r that a test of r = 0 finds with 80 % power at this n; dof = n - 2."""
    r = validation.real("r", r)
    if not -1 < r < 1:
        raise ValueError(f"r must lie in (-1, 1) (Fisher's z is infinite at +-1), got {r!r}")
    return _fisher(r, validation.integer("n", n, minimum=4))


def _fisher(r: float, n: int) -> Test:
    z, se = math.atanh(r), 1 / math.sqrt(n - 3)
    crit = scipy_stats.norm.ppf(0.5 + LEVEL / 2)
    detectable = math.tanh((crit + scipy_stats.norm.ppf(POWER)) * se)
    t = r * math.sqrt((n - 2) / (1 - r * r))  # the t of r = 0, n - 2 dof
    p = float(2 * scipy_stats.t.sf(abs(t), n - 2))
    low, high = math.tanh(z - crit * se), math.tanh(z + crit * se)
    return Test("Fisher z", r, low, high, n - 2, p, detectable, n, t)


def power_at(test: Test, effect: float) -> float:
    """The power of ``test``'s design to detect a true ``effect`` (two-sided 5 %), at its
    standard error and degrees of freedom (the test must have both: dof, and an interval
    of positive width)."""
    validation.instance("test", test, Test)
    effect = validation.real("effect", effect)
    if math.isnan(test.dof) or test.low == test.high:
        raise ValueError(f"test needs a dof and an interval of some width, got {test!r}")
    dist = scipy_stats.norm if math.isinf(test.dof) else scipy_stats.t(test.dof)
    crit = float(dist.ppf(0.5 + LEVEL / 2))
    se = (test.high - test.low) / (2 * crit)
    shift = abs(effect) / se
    return float(dist.sf(crit - shift) + dist.cdf(-crit - shift))


def holm(p: list[float]) -> list[float]:
    """Holm's step-down adjusted p-values of one family of tests, in the order given: the
    i-th smallest p times (m - i + 1), made non-decreasing, at most 1. A ``nan`` p (a test
    with none) stays ``nan`` and is not counted in the family's m. Rejecting where the
    adjusted p < alpha keeps the chance of any false rejection in the family <= alpha."""
    values = [validation.real("p", x) if not math.isnan(x) else x for x in p]
    order = sorted((x, i) for i, x in enumerate(values) if not math.isnan(x))
    m, adjusted, running = len(order), [math.nan] * len(values), 0.0
    for rank, (x, i) in enumerate(order):
        running = max(running, min(1.0, (m - rank) * x))
        adjusted[i] = running
    return adjusted


def sem(values, axis: int = 0) -> np.ndarray:
    """Standard error of the mean along ``axis`` (ddof=1)."""
    values = validation.real_array("values", values)
    axis = validation.integer("axis", axis, minimum=None)
    if not -values.ndim <= axis < values.ndim:
        raise ValueError(f"axis {axis} is out of range for values of shape {values.shape}")
    if values.shape[axis] < 2:
        raise ValueError("the standard error needs at least 2 values along the axis")
    return values.std(axis=axis, ddof=1) / np.sqrt(values.shape[axis])


def mean_ci(values, level: float = LEVEL) -> tuple[float, float, float]:
    """Mean and Student-t confidence interval (mean, low, high) of a 1-D sample that varies."""
    level = validation.fraction("level", level)
    return _t_interval(validation.varying("values", validation.sample("values", values)), level)


def _t_interval(x: np.ndarray, level: float = LEVEL) -> tuple[float, float, float]:
    """The mean of ``x`` (at least 2 values) and its Student-t interval at ``level``."""
    half = float(scipy_stats.t.ppf(0.5 + level / 2, x.size - 1) * sem(x))
    mean = float(x.mean())
    return mean, mean - half, mean + half


def _pair(names: tuple[str, str], x, y) -> tuple[np.ndarray, np.ndarray]:
    """Two samples of the same length."""
    x, y = validation.sample(names[0], x), validation.sample(names[1], y)
    if x.shape != y.shape:
        raise ValueError(
            f"{' and '.join(names)} must have the same length, got {x.size} and {y.size}"
        )
    return x, y


def inverse_variance(estimates, ses) -> dict:
    """Fixed-effect pooling of per-genome ``estimates`` with standard errors ``ses``
    (weights 1 / se^2): the pooled estimate, its SE and normal 95 % interval; Cochran's Q
    (k - 1 dof) with its p and I^2; the DerSimonian-Laird between-genome variance tau^2
    and the random-effects estimate (weights 1 / (se^2 + tau^2)) with its interval."""
    x = np.asarray(estimates, dtype=np.float64)
    w = 1 / np.asarray(ses, dtype=np.float64) ** 2
    crit = scipy_stats.norm.ppf(0.5 + LEVEL / 2)
    pooled, se = float((w * x).sum() / w.sum()), float(1 / math.sqrt(w.sum()))
    q, dof = float((w * (x - pooled) ** 2).sum()), x.size - 1
    tau2 = max(0.0, (q - dof) / (w.sum() - (w**2).sum() / w.sum())) if dof > 0 else math.nan
    w_re = 1 / (1 / w + (tau2 if dof > 0 else 0.0))
    random, se_re = float((w_re * x).sum() / w_re.sum()), float(1 / math.sqrt(w_re.sum()))
    return {
        "estimate": pooled,
        "se": se,
        "ci": (pooled - crit * se, pooled + crit * se),
        "q": q,
        "q_dof": dof,
        "q_p": float(scipy_stats.chi2.sf(q, dof)) if dof > 0 else math.nan,
        "i2": max(0.0, (q - dof) / q) if q > 0 else 0.0,
        "tau2": tau2,
        "random_effects": random,
        "random_effects_se": se_re,
        "random_effects_ci": (random - crit * se_re, random + crit * se_re),
    }


def between_genomes(estimates) -> dict:
    """The spread of per-genome ``estimates``: their mean, SD and Student-t 95 % interval
    over genomes (k - 1 dof): what a claim about genomes of this setting in general can
    lean on. With 3 genomes that is 2 dof (t = 4.30): only a spread far above the
    estimates' own errors shows, and the interval is wide."""
    x = np.asarray(estimates, dtype=np.float64)
    if x.size < 2:
        return {"n_genomes": 1, "mean": float(x[0]), "sd": math.nan, "ci": (math.nan, math.nan)}
    mean, low, high = (float(v) for v in _t_interval(x))
    return {"n_genomes": int(x.size), "mean": mean, "sd": float(x.std(ddof=1)), "ci": (low, high)}


def between_genomes_r(rs) -> dict:
    """``between_genomes`` of correlations, on Fisher's z: the mean and interval back on
    the r scale, the SD (``z_sd``) on the z scale."""
    z = np.arctanh(np.clip(np.asarray(rs, dtype=np.float64), -1 + 1e-12, 1 - 1e-12))
    out = between_genomes(z)
    out["z_sd"] = out.pop("sd")
    out["mean"], out["ci"] = math.tanh(out["mean"]), tuple(np.tanh(out["ci"]).tolist())
    return out


def pooled_r(rs, ns) -> dict:
    """Per-genome correlations ``rs`` of ``ns`` pairs pooled by Fisher z (weights n - 3):
    ``inverse_variance`` on z, with the estimate and intervals back on the r scale."""
    z = np.arctanh(np.clip(np.asarray(rs, dtype=np.float64), -1 + 1e-12, 1 - 1e-12))
    pooled = inverse_variance(z, 1 / np.sqrt(np.asarray(ns, dtype=np.float64) - 3))
    out = {"z_se": pooled.pop("se"), "random_effects_z_se": pooled.pop("random_effects_se")}
    for key in ("estimate", "random_effects"):
        pooled[key] = math.tanh(pooled[key])
    for key in ("ci", "random_effects_ci"):
        pooled[key] = tuple(math.tanh(v) for v in pooled[key])
    return {**pooled, **out}


def _log_curve(side: str, x, y) -> tuple[np.ndarray, np.ndarray]:
    """Curve ``side``'s log(x) and y: x positive and strictly increasing, y as long."""
    x, y = _pair((f"x_{side}", f"y_{side}"), x, y)
    if x.min() <= 0:
        raise ValueError(f"x_{side} must be positive (curves meet in log x), got {x.min():g}")
    if np.any(np.diff(x) <= 0):
        raise ValueError(f"x_{side} must be strictly increasing, got {x.tolist()}")
    return np.log(x), y


def crossings(x_a, y_a, x_b, y_b, rising: bool = False) -> list[float]:
    """Where curve a minus curve b changes sign, in x, low to high; with ``rising``, only
    where it goes from below 0 to above (a overtakes b).

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
    changes = np.sign(diff[:-1]) * np.sign(diff[1:]) < 0
    if rising:
        changes &= diff[:-1] < 0
    for i in np.nonzero(changes)[0]:
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
    rising: bool = False,
) -> CrossingInterval:
    """The first crossing of the mean curves of ``a`` and ``b`` (``crossings``; with
    ``rising``, the first where a overtakes b), with a parametric bootstrap interval.

    ``a`` and ``b`` map x (a compression ratio) to the values of the seeds run there, at
    least two per point. Each simulated curve draws every point's mean from its Student-t
    sampling distribution (the seeds' mean, their SEM, n - 1 degrees of freedom), point by
    point and independently. Resampling the seeds instead undercovers at the few seeds
    sweeps have: on curves with a known crossing it covered it in 77 % of 150 trials at 3
    seeds and 87 % at 5, the t draws in 99 % and 97 % (the curves of ``tests/test_stats``)."""
    draws = validation.integer("draws", draws)
    level = validation.fraction("level", level)
    rng = np.random.default_rng(validation.seed("seed", seed))
    (xa, ma, sa, da), (xb, mb, sb, db) = _mean_curve("a", a), _mean_curve("b", b)
    first = crossings(xa, ma, xb, mb, rising)
    found = []
    for _ in range(draws):
        ya = ma + sa * rng.standard_t(da)
        yb = mb + sb * rng.standard_t(db)
        points = crossings(xa, ya, xb, yb, rising)
        if points:
            found.append(points[0])
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(found, [tail, 100 - tail]) if found else (np.nan, np.nan)
    estimate = first[0] if first else np.nan
    return CrossingInterval(float(estimate), float(low), float(high), len(found) / draws, draws)
