"""How well k episodes tell individuals apart: the one-way variance split of a population's
returns, the intraclass correlation with its F interval, and Spearman-Brown projections.

For returns ``x`` of shape (N individuals, k episodes), one-way ANOVA gives the mean squares
between individuals (MSB, N - 1 dof) and within (MSW, N (k - 1) dof). Then:

- within-individual variance ``sigma_w^2 = MSW`` (episode noise);
- between-individual variance ``sigma_b^2 = max(0, (MSB - MSW) / k)``;
- ``icc`` = ICC(1) = (MSB - MSW) / (MSB + (k - 1) MSW): the reliability of one episode;
- ``reliability`` = ICC(1, k) = 1 - MSW / MSB: the reliability of a k-episode mean, the
  correlation expected between two independent k-episode means of the same individuals.

Intervals come from F = MSB / MSW, distributed F(N - 1, N (k - 1)) times
(1 + k sigma_b^2 / sigma_w^2) (Shrout and Fleiss, 1979).
"""

import math
from typing import NamedTuple

from scipy import stats as scipy_stats

from sgb import validation


class VarianceSplit(NamedTuple):
    """The split of one population's returns, with 95 % intervals (low, high)."""

    n_individuals: int
    episodes: int
    between_var: float
    within_var: float
    icc: float
    icc_ci: tuple[float, float]
    reliability: float
    reliability_ci: tuple[float, float]
    f: float
    p: float


def variance_split(returns, level: float = 0.95, crossed: bool = False) -> VarianceSplit:
    """One-way random-effects split of ``returns`` (N, k), N >= 2, k >= 2, with intervals
    at ``level`` in (0, 1). The individuals' means must differ and so must the episodes of
    at least one individual (else F is 0 or infinite). ``crossed``: every individual met
    the same k conditions (parts of one test set), whose shared effect is taken out first
    (two-way without replication: within is the residual, on (N - 1)(k - 1) dof)."""
    x = validation.real_array("returns", returns, ndim=2)
    if min(x.shape) < 2:
        raise ValueError(f"returns must have N >= 2 individuals and k >= 2 episodes, got {x.shape}")
    level = validation.fraction("level", level)
    n, k = x.shape
    means = x.mean(axis=1)
    msb = k * means.var(ddof=1)
    residual = x - means[:, None]
    if crossed:
        residual = residual - residual.mean(axis=0)
    df2 = (n - 1) * (k - 1) if crossed else n * (k - 1)
    msw = (residual**2).sum() / df2
    if msw <= 0:
        raise ValueError("returns: every individual's episodes are identical, so F is infinite")
    if msb <= 0:
        raise ValueError("returns: every individual has the same mean, so F is 0")
    f = float(msb / msw)
    df1 = n - 1
    upper = scipy_stats.f.ppf(0.5 + level / 2, df1, df2)
    lower = scipy_stats.f.ppf(0.5 - level / 2, df1, df2)
    f_low, f_high = f / upper, f / lower

    def icc_of(value: float) -> float:
        return float((value - 1) / (value + k - 1))

    def reliability_of(value: float) -> float:
        return float(1 - 1 / value)

    return VarianceSplit(
        n_individuals=n,
        episodes=k,
        between_var=float(max(0.0, (msb - msw) / k)),
        within_var=float(msw),
        icc=icc_of(f),
        icc_ci=(icc_of(f_low), icc_of(f_high)),
        reliability=reliability_of(f),
        reliability_ci=(reliability_of(f_low), reliability_of(f_high)),
        f=f,
        p=float(scipy_stats.f.sf(f, df1, df2)),
    )


def _icc(name: str, icc: float) -> float:
    """A one-episode intraclass correlation: a real number in [-1, 1]."""
    return validation.in_range(name, icc, -1.0, 1.0)


def projected_reliability(icc: float, episodes: float) -> float:
    """Spearman-Brown: the reliability of an ``episodes``-episode mean (episodes > 0) from a
    one-episode ``icc`` in [-1, 1], where 1 + (episodes - 1) icc > 0."""
    icc, episodes = _icc("icc", icc), validation.positive("episodes", episodes)
    scale = 1 + (episodes - 1) * icc
    if scale <= 0:
        raise ValueError(
            f"icc {icc!r} is too negative for {episodes!r} episodes: 1 + (m - 1) icc <= 0"
        )
    return episodes * icc / scale


def episodes_for(icc: float, target: float = 0.8) -> float:
    """Episodes per individual whose mean reaches reliability ``target`` in (0, 1)
    (Spearman-Brown) from a one-episode ``icc`` in [-1, 1]; ``inf`` when the individuals do
    not differ (``icc <= 0``)."""
    icc, target = _icc("icc", icc), validation.fraction("target", target)
    if icc <= 0:
        return math.inf
    return target * (1 - icc) / (icc * (1 - target))


def between_sd_bound(split: VarianceSplit) -> float:
    """An upper bound on the SD between individuals, from the upper end of the ICC's
    interval (below 1): sigma_b^2 <= icc_high / (1 - icc_high) * sigma_w^2."""
    validation.instance("split", split, VarianceSplit)
    icc_high = _icc("split.icc_ci[1]", split.icc_ci[1])
    within = validation.non_negative("split.within_var", split.within_var)
    if icc_high == 1:
        raise ValueError("split.icc_ci[1] must be below 1: at 1 the bound is infinite")
    return between_sd_at(icc_high, within)


def between_sd_at(icc: float, within_var: float) -> float:
    """The SD between individuals that a one-episode ``icc`` below 1 implies beside the
    within-individual variance ``within_var``: sqrt(icc / (1 - icc) * within_var), 0 where
    the ICC is 0 or below (same units as the returns)."""
    icc, within = _icc("icc", icc), validation.non_negative("within_var", within_var)
    if icc == 1:
        raise ValueError("icc must be below 1: at 1 the SD between individuals is infinite")
    return math.sqrt(max(icc, 0.0) / (1 - icc) * within)


def detectable_between_sd(
    n: int, k: int, within_sd: float, level: float = 0.95, power: float = 0.8
) -> float:
    """The smallest SD between individuals that the one-way F-test of N individuals x k
    episodes finds (one-sided, at 1 - ``level``) with probability ``power``, at a
    within-individual SD ``within_sd``: under sigma_b^2 = theta sigma_w^2, F / (1 + k theta)
    is F(N - 1, N (k - 1)), so theta = (F_crit / F_(1 - power) - 1) / k."""
    n, k = validation.integer("n", n, minimum=2), validation.integer("k", k, minimum=2)
    within_sd = validation.non_negative("within_sd", within_sd)
    level, power = validation.fraction("level", level), validation.fraction("power", power)
    df1, df2 = n - 1, n * (k - 1)
    ratio = scipy_stats.f.ppf(level, df1, df2) / scipy_stats.f.ppf(1 - power, df1, df2)
    return within_sd * math.sqrt((ratio - 1) / k)


def episodes_to_detect(n: int, within_sd: float, target_sd: float, most: int = 10**6) -> int:
    """The fewest episodes per individual (at least 2) at which ``detectable_between_sd``
    of N individuals falls to ``target_sd`` > 0 (it falls as episodes grow); ``most`` if
    even that many do not reach it."""
    target_sd = validation.positive("target_sd", target_sd)
    if detectable_between_sd(n, most, within_sd) > target_sd:
        return most
    low, high = 2, most  # detectable at high <= target
    while low < high:
        mid = (low + high) // 2
        if detectable_between_sd(n, mid, within_sd) <= target_sd:
            high = mid
        else:
            low = mid + 1
    return low
