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

import numpy as np
from scipy import stats as scipy_stats


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


def variance_split(returns, level: float = 0.95) -> VarianceSplit:
    """One-way random-effects split of ``returns`` (N, k), N >= 2, k >= 2."""
    x = np.asarray(returns, dtype=np.float64)
    if x.ndim != 2 or min(x.shape) < 2 or not np.all(np.isfinite(x)):
        raise ValueError(f"returns must be a finite (N, k) array, N and k >= 2; got {x.shape}")
    n, k = x.shape
    means = x.mean(axis=1)
    msb = k * means.var(ddof=1)
    msw = ((x - means[:, None]) ** 2).sum() / (n * (k - 1))
    if msw <= 0:
        raise ValueError("every individual's episodes are identical: the split is undefined")
    f = msb / msw
    df1, df2 = n - 1, n * (k - 1)
    upper = scipy_stats.f.ppf(0.5 + level / 2, df1, df2)
    lower = scipy_stats.f.ppf(0.5 - level / 2, df1, df2)
    f_low, f_high = f / upper, f / lower

    def icc_of(value: float) -> float:
        return (value - 1) / (value + k - 1)

    return VarianceSplit(
        n_individuals=n,
        episodes=k,
        between_var=max(0.0, (msb - msw) / k),
        within_var=float(msw),
        icc=icc_of(f),
        icc_ci=(icc_of(f_low), icc_of(f_high)),
        reliability=1 - 1 / f,
        reliability_ci=(1 - 1 / f_low, 1 - 1 / f_high),
        f=float(f),
        p=float(scipy_stats.f.sf(f, df1, df2)),
    )


def projected_reliability(icc: float, episodes: int) -> float:
    """Spearman-Brown: the reliability of an ``episodes``-episode mean from a one-episode
    ``icc``."""
    return episodes * icc / (1 + (episodes - 1) * icc)


def episodes_for(icc: float, target: float = 0.8) -> float:
    """Episodes per individual whose mean reaches reliability ``target`` (Spearman-Brown);
    ``inf`` when the individuals do not differ (``icc <= 0``)."""
    if not 0 < target < 1:
        raise ValueError(f"target must lie in (0, 1), got {target}")
    if icc <= 0:
        return math.inf
    return target * (1 - icc) / (icc * (1 - target))


def between_sd_bound(split: VarianceSplit) -> float:
    """An upper bound on the SD between individuals, from the upper end of the ICC's
    interval: sigma_b^2 <= icc_high / (1 - icc_high) * sigma_w^2."""
    icc_high = split.icc_ci[1]
    if icc_high <= 0:
        return 0.0
    return math.sqrt(icc_high / (1 - icc_high) * split.within_var)
