"""Tests with their 95 % intervals and power, and the one rule that turns them into verdicts.

Every test here estimates an *effect* (a difference of means, or a correlation), with a
two-sided 95 % confidence interval and the *detectable effect*: the smallest true effect
that the test would find (p < 0.05, two-sided) with 80 % power at this sample size.

The rule, for a claim whose paper effect is ``paper`` against a null ``null`` (no effect):

- **reproduced**: the interval excludes the null, on the paper's side of it, and holds the
  paper's effect (or the effect that stands in for it);
- **reproduced in direction, smaller (larger) than the effect compared**: the interval
  excludes the null on the paper's side, and the paper's effect (or its stand-in) on the
  far (near) side: the direction holds, the size does not;
- **contradicted**: otherwise, if the interval excludes the paper's effect;
- **inconclusive at this budget**: neither; the budget that would decide is the sample
  size at which the detectable effect shrinks to the paper's (``units_to_decide``);
- **not testable here**: no run here can test the claim (a reason is given instead).
"""

import math
from typing import NamedTuple

import numpy as np
from scipy import stats as scipy_stats

from sgb import validation

LEVEL = 0.95
POWER = 0.8
REPRODUCED = "reproduced"
# smaller or larger than the effect the row compares: the paper's, or its stand-in
SMALLER = "reproduced in direction, smaller than the effect compared"
LARGER = "reproduced in direction, larger than the effect compared"
CONTRADICTED = "contradicted"
INCONCLUSIVE = "inconclusive at this budget"
NOT_TESTABLE = "not testable here"
IN_DIRECTION = (REPRODUCED, SMALLER, LARGER)  # the paper's direction holds
VERDICTS = (*IN_DIRECTION, CONTRADICTED, INCONCLUSIVE, NOT_TESTABLE)


class _Fields(NamedTuple):
    name: str
    estimate: float
    low: float
    high: float
    dof: float
    p: float
    detectable: float
    n: int


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
    p = 2 * dist.sf(abs(estimate - null) / se)
    return Test(name, estimate, estimate - half, estimate + half, dof, float(p), detectable, n)


def welch(a, b) -> Test:
    """Welch's t for mean(a) - mean(b) of two independent samples (Welch-Satterthwaite
    degrees of freedom), not both constant; ``n`` is the smaller sample's size."""
    a, b = validation.sample("a", a), validation.sample("b", b)
    if np.ptp(a) == 0 and np.ptp(b) == 0:
        raise ValueError("a and b are both constant, so the statistic is undefined")
    va, vb = a.var(ddof=1) / a.size, b.var(ddof=1) / b.size
    dof = (va + vb) ** 2 / (va**2 / (a.size - 1) + vb**2 / (b.size - 1))
    return _t_test("Welch t", a.mean() - b.mean(), math.sqrt(va + vb), dof, min(a.size, b.size), 0)


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
    p = float(2 * scipy_stats.t.sf(abs(r) * math.sqrt((n - 2) / (1 - r * r)), n - 2))
    return Test(
        "Fisher z", r, math.tanh(z - crit * se), math.tanh(z + crit * se), n - 2, p, detectable, n
    )


def _effect(test: Test, paper: float, null: float) -> tuple[float, float]:
    """``paper`` and ``null`` checked against ``test``: finite, and apart (the rule needs
    the paper's side of the null)."""
    validation.instance("test", test, Test)
    paper, null = validation.real("paper", paper), validation.real("null", null)
    if paper == null:
        raise ValueError(f"paper must differ from null ({null!r}): an effect of none has no side")
    return paper, null


def verdict(test: Test, paper: float, null: float = 0.0) -> str:
    """The rule of the module docstring: ``REPRODUCED``, ``SMALLER``, ``LARGER``,
    ``CONTRADICTED`` or ``INCONCLUSIVE``."""
    paper, null = _effect(test, paper, null)
    if (paper > null and test.low > null) or (paper < null and test.high < null):
        if paper_inside(test, paper):
            return REPRODUCED
        beyond = test.low > paper if paper > null else test.high < paper
        return LARGER if beyond else SMALLER
    if not test.low <= paper <= test.high:
        return CONTRADICTED
    return INCONCLUSIVE


def paper_inside(test: Test, paper: float) -> bool:
    """Whether the paper's effect lies inside the test's interval."""
    validation.instance("test", test, Test)
    return test.low <= validation.real("paper", paper) <= test.high


def units_to_decide(test: Test, paper: float, null: float = 0.0) -> int:
    """The sample size (per group, in the test's units) at which the detectable effect
    equals the paper's, scaling the standard error as 1/sqrt(n) (for r, through Fisher's
    z, where the paper's r must lie in (-1, 1))."""
    paper, null = _effect(test, paper, null)
    effect = abs(paper - null)
    if test.name == "Fisher z":
        if effect >= 1:
            raise ValueError(f"paper must be a correlation in (-1, 1), got {paper!r}")
        crit = scipy_stats.norm.ppf(0.5 + LEVEL / 2) + scipy_stats.norm.ppf(POWER)
        units = _squared(crit / math.atanh(effect)) + 3
    elif math.isnan(test.detectable):
        raise ValueError(f"test has no detectable effect to scale ({test.name})")
    else:
        units = test.n * _squared(test.detectable / effect)
    if not math.isfinite(units):
        raise ValueError(f"no finite sample size detects paper = {paper!r} with this test")
    return math.ceil(units)


def _squared(x: float) -> float:
    """``x * x``, ``inf`` where it overflows (``x ** 2`` raises there)."""
    return x * x


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
