"""Tests with their 95 % intervals and power, and the one rule that turns them into verdicts.

Every test here estimates an *effect* (a difference of means, or a correlation), with a
two-sided 95 % confidence interval and the *detectable effect*: the smallest true effect
that the test would find (p < 0.05, two-sided) with 80 % power at this sample size.

The rule, for a claim whose paper effect is ``paper`` against a null ``null`` (no effect):

- **reproduced**: the interval excludes the null, on the paper's side of it;
- **contradicted**: otherwise, if the interval excludes the paper's effect;
- **inconclusive at this budget**: neither; the budget that would decide is the sample
  size at which the detectable effect shrinks to the paper's (``units_to_decide``);
- **not testable here**: no run here can test the claim (a reason is given instead).

A claim reproduced in direction may still differ in size: ``paper_inside`` says whether
the paper's effect lies inside the interval.
"""

import math
from typing import NamedTuple

import numpy as np
from scipy import stats as scipy_stats

from sgb import validation

LEVEL = 0.95
POWER = 0.8
REPRODUCED = "reproduced"
CONTRADICTED = "contradicted"
INCONCLUSIVE = "inconclusive at this budget"
NOT_TESTABLE = "not testable here"
VERDICTS = (REPRODUCED, CONTRADICTED, INCONCLUSIVE, NOT_TESTABLE)


class Test(NamedTuple):
    """One test: its name, the effect estimated, its 95 % interval (low, high), degrees of
    freedom (``inf`` for a normal approximation), two-sided p against the null, the
    effect detectable at 80 % power, and the sample size ``n`` per group."""

    name: str
    estimate: float
    low: float
    high: float
    dof: float
    p: float
    detectable: float
    n: int


def _sample(name: str, values) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 1 or array.size < 2 or not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be a 1-D sequence of at least 2 finite numbers")
    return array


def _t_test(name: str, estimate: float, se: float, dof: float, n: int, null: float) -> Test:
    """A t (or, for ``dof=inf``, z) test of ``estimate`` with standard error ``se``."""
    if not se > 0:
        raise ValueError(f"{name}: the standard error must be positive, got {se}")
    dist = scipy_stats.norm if math.isinf(dof) else scipy_stats.t(dof)
    half = dist.ppf(0.5 + LEVEL / 2) * se
    detectable = (dist.ppf(0.5 + LEVEL / 2) + dist.ppf(POWER)) * se
    p = 2 * dist.sf(abs(estimate - null) / se)
    return Test(name, estimate, estimate - half, estimate + half, dof, float(p), detectable, n)


def welch(a, b) -> Test:
    """Welch's t for mean(a) - mean(b) of two independent samples (Welch-Satterthwaite
    degrees of freedom); ``n`` is the smaller sample's size."""
    a, b = _sample("a", a), _sample("b", b)
    va, vb = a.var(ddof=1) / a.size, b.var(ddof=1) / b.size
    dof = (va + vb) ** 2 / (va**2 / (a.size - 1) + vb**2 / (b.size - 1))
    return _t_test("Welch t", a.mean() - b.mean(), math.sqrt(va + vb), dof, min(a.size, b.size), 0)


def paired(a, b) -> Test:
    """Paired t for mean(a - b) (same units measured twice); dof = n - 1."""
    a, b = _sample("a", a), _sample("b", b)
    if a.shape != b.shape:
        raise ValueError(f"a and b must have the same length, got {a.size} and {b.size}")
    d = a - b
    return _t_test("paired t", d.mean(), d.std(ddof=1) / math.sqrt(d.size), d.size - 1, d.size, 0)


def one_sample(values, null: float) -> Test:
    """One-sample t of mean(values) against a fixed ``null``; dof = n - 1."""
    v = _sample("values", values)
    se = v.std(ddof=1) / math.sqrt(v.size)
    return _t_test("one-sample t", v.mean(), se, v.size - 1, v.size, validation.real("null", null))


def estimate_test(name: str, estimate: float, stderr: float, n: int) -> Test:
    """A z test of a Monte Carlo estimate with its standard error (normal approximation)."""
    return _t_test(name, float(estimate), float(stderr), math.inf, n, 0)


def fisher_r(x, y) -> Test:
    """Pearson's r with its Fisher-z interval; detectable: the r that a test of r = 0 finds
    with 80 % power at this n; dof = n - 2."""
    x, y = _sample("x", x), _sample("y", y)
    if x.shape != y.shape or x.size < 4:
        raise ValueError("x and y must have the same length, at least 4")
    r = float(np.corrcoef(x, y)[0, 1])
    return fisher_from_r(r, x.size)


def fisher_from_r(r: float, n: int) -> Test:
    """``fisher_r`` from a correlation ``r`` of ``n`` pairs."""
    z, se = math.atanh(max(min(r, 1 - 1e-12), -1 + 1e-12)), 1 / math.sqrt(n - 3)
    crit = scipy_stats.norm.ppf(0.5 + LEVEL / 2)
    detectable = math.tanh((crit + scipy_stats.norm.ppf(POWER)) * se)
    t = r * math.sqrt((n - 2) / max(1 - r * r, 1e-300))
    p = float(2 * scipy_stats.t.sf(abs(t), n - 2))
    return Test(
        "Fisher z", r, math.tanh(z - crit * se), math.tanh(z + crit * se), n - 2, p, detectable, n
    )


def verdict(test: Test, paper: float, null: float = 0.0) -> str:
    """The rule of the module docstring."""
    side = math.copysign(1.0, paper - null)
    if (side > 0 and test.low > null) or (side < 0 and test.high < null):
        return REPRODUCED
    if not test.low <= paper <= test.high:
        return CONTRADICTED
    return INCONCLUSIVE


def paper_inside(test: Test, paper: float) -> bool:
    """Whether the paper's effect lies inside the test's interval."""
    return test.low <= paper <= test.high


def units_to_decide(test: Test, paper: float, null: float = 0.0) -> int:
    """The sample size (per group, in the test's units) at which the detectable effect
    equals the paper's, scaling the standard error as 1/sqrt(n) (for r, through Fisher's z)."""
    effect = abs(paper - null)
    if effect == 0:
        raise ValueError("the paper's effect equals the null: no sample size decides it")
    if test.name == "Fisher z":
        crit = scipy_stats.norm.ppf(0.5 + LEVEL / 2) + scipy_stats.norm.ppf(POWER)
        return math.ceil((crit / math.atanh(min(effect, 1 - 1e-12))) ** 2 + 3)
    return math.ceil(test.n * (test.detectable / effect) ** 2)


def power_at(test: Test, effect: float) -> float:
    """The power of ``test``'s design to detect a true ``effect`` (two-sided 5 %), at its
    standard error and degrees of freedom."""
    dist = scipy_stats.norm if math.isinf(test.dof) else scipy_stats.t(test.dof)
    crit = dist.ppf(0.5 + LEVEL / 2)
    se = (test.high - test.low) / (2 * crit)
    shift = abs(effect) / se
    return float(dist.sf(crit - shift) + dist.cdf(-crit - shift))
