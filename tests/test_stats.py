"""``sgb.stats``: each test agrees with scipy, its interval covers the truth at the stated
rate, its detectable effect has the stated power; crossings, Holm's correction."""

import math

import numpy as np
import pytest
from scipy import stats as scipy_stats

from sgb import stats, verdicts


def test_welch_agrees_with_scipy_and_its_interval_covers_the_truth():
    rng = np.random.default_rng(0)
    a, b = rng.normal(1.0, 1.0, 7), rng.normal(0.0, 2.0, 11)
    test = stats.welch(a, b)
    reference = scipy_stats.ttest_ind(a, b, equal_var=False)
    assert test.p == pytest.approx(reference.pvalue, rel=1e-9)
    covered = 0
    for _ in range(2000):
        t = stats.welch(rng.normal(1.0, 1.0, 7), rng.normal(0.0, 2.0, 11))
        covered += t.low <= 1.0 <= t.high
    assert 0.935 <= covered / 2000 <= 0.965


def test_a_contrast_of_three_arms_covers_its_truth_and_welch_is_its_two_arm_case():
    rng = np.random.default_rng(12)
    a, b = rng.normal(1.0, 1.0, 7), rng.normal(0.0, 2.0, 11)
    assert stats.contrast([a, b], [1.0, -1.0])._replace(name="Welch t") == stats.welch(a, b)
    means, sds, sizes, w = (0.9, 0.7, 0.2), (0.1, 0.3, 0.05), (3, 5, 4), (-1.0, 2.0, -1.0)
    truth = float(np.dot(w, means))  # 0.3
    arms = [rng.normal(m, sd, n) for m, sd, n in zip(means, sds, sizes, strict=True)]
    test = stats.contrast(arms, w)
    se = math.sqrt(sum(wi**2 * x.var(ddof=1) / x.size for wi, x in zip(w, arms, strict=True)))
    assert test.estimate == pytest.approx(float(np.dot(w, [x.mean() for x in arms])))
    assert (test.high - test.low) / 2 == pytest.approx(scipy_stats.t(test.dof).ppf(0.975) * se)
    assert test.n == 3
    covered = 0
    for _ in range(2000):
        t = stats.contrast(
            [rng.normal(m, sd, n) for m, sd, n in zip(means, sds, sizes, strict=True)], w
        )
        covered += t.low <= truth <= t.high
    assert 0.935 <= covered / 2000 <= 0.965
    with pytest.raises(ValueError, match="one weight per sample"):
        stats.contrast(arms, w[:2])


def test_the_detectable_effect_has_80_percent_power():
    """At the detectable effect of a design, the test finds the effect 80 % of the time,
    and units_to_decide gives the sample size at which a smaller effect is detectable."""
    rng = np.random.default_rng(1)
    sd = 1.0
    effect = 0.5
    probe = stats.welch(rng.normal(effect, sd, 400), rng.normal(0, sd, 400))
    needed = verdicts.units_to_decide(probe, effect)
    found = sum(
        verdicts.verdict(
            stats.welch(rng.normal(effect, sd, needed), rng.normal(0, sd, needed)), effect
        )
        == verdicts.REPRODUCED
        for _ in range(600)
    )
    assert 0.72 <= found / 600 <= 0.88  # about 80 % power at the size it names
    design = stats.welch(rng.normal(effect, sd, needed), rng.normal(0, sd, needed))
    assert stats.power_at(design, design.detectable) == pytest.approx(0.8, abs=0.01)


def test_paired_and_one_sample_agree_with_scipy():
    rng = np.random.default_rng(3)
    a = rng.normal(size=20)
    b = a + rng.normal(0.3, 0.2, 20)
    assert stats.paired(b, a).p == pytest.approx(scipy_stats.ttest_rel(b, a).pvalue, rel=1e-9)
    assert stats.one_sample(a, 0.5).p == pytest.approx(scipy_stats.ttest_1samp(a, 0.5).pvalue)


def test_fisher_interval_covers_the_true_correlation():
    rng = np.random.default_rng(4)
    rho, n, covered = 0.5, 50, 0
    cov = [[1, rho], [rho, 1]]
    for _ in range(1000):
        x, y = rng.multivariate_normal([0, 0], cov, n).T
        t = stats.fisher_r(x, y)
        covered += t.low <= rho <= t.high
    assert 0.93 <= covered / 1000 <= 0.97
    x, y = rng.multivariate_normal([0, 0], cov, n).T
    assert stats.fisher_r(x, y).p == pytest.approx(scipy_stats.pearsonr(x, y).pvalue, rel=1e-6)
    # the n at which r = 0.3 is detectable at 80 % power: the textbook 85
    assert verdicts.units_to_decide(stats.fisher_r(x, y), 0.3) == 85


def _crossing_curves(rng, seeds: int, noise: float) -> tuple[dict, dict, float]:
    """Accuracy curves, linear in log(ratio), that cross at ratio 60: a falls faster."""
    ratios = np.array([10.0, 20.0, 50.0, 100.0, 200.0, 400.0, 700.0])
    mean_a = 0.9 - 0.05 * np.log(ratios / 60)
    mean_b = 0.9 - 0.02 * np.log(ratios / 60)
    a = {x: m + noise * rng.standard_normal(seeds) for x, m in zip(ratios, mean_a, strict=True)}
    b = {x: m + noise * rng.standard_normal(seeds) for x, m in zip(ratios, mean_b, strict=True)}
    return a, b, 60.0


def test_the_bootstrap_crossing_finds_a_known_crossing_and_its_interval_covers_it():
    rng = np.random.default_rng(0)
    a, b, true = _crossing_curves(rng, seeds=3, noise=0.0)
    exact = stats.bootstrap_crossing(a, b, draws=50)
    assert exact.estimate == pytest.approx(true) and exact.share_crossing == 1.0
    assert exact.low == pytest.approx(true) and exact.high == pytest.approx(true)
    for seeds in (3, 5):
        covered, widths = [], []
        for _ in range(60):
            a, b, true = _crossing_curves(rng, seeds=seeds, noise=0.01)
            found = stats.bootstrap_crossing(a, b, draws=200, seed=1)
            covered.append(found.low <= true <= found.high)
            widths.append(found.high / found.low)
        assert np.mean(covered) >= 0.9, seeds
        assert 1.0 < np.median(widths) < (8.0 if seeds == 3 else 4.0)


def test_curves_that_do_not_cross_give_no_crossing():
    rng = np.random.default_rng(1)
    a, b, _ = _crossing_curves(rng, seeds=4, noise=0.005)
    apart = {x: v + 1.0 for x, v in b.items()}  # b lifted far above a everywhere
    found = stats.bootstrap_crossing(a, apart, draws=100)
    assert np.isnan(found.estimate) and np.isnan(found.low) and found.share_crossing == 0.0


def test_holm_adjusts_a_known_family_and_keeps_the_familywise_error():
    """A textbook family by hand; nan left out of m; under the global null with eight
    independent tests, any adjusted p < 0.05 in at most 5 % of families (Monte Carlo),
    where the raw p would reject in about 34 %."""
    got = stats.holm([0.01, 0.04, 0.03, 0.005, math.nan])
    assert got[:4] == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert math.isnan(got[4])
    assert stats.holm([0.5, 0.9]) == pytest.approx([1.0, 1.0])
    rng = np.random.default_rng(0)
    families = rng.uniform(size=(20_000, 8))
    raw = np.mean((families < 0.05).any(axis=1))
    holm = np.mean([min(stats.holm(list(f))) < 0.05 for f in families])
    assert raw > 0.3 and holm < 0.05 + 3 * math.sqrt(0.05 * 0.95 / 20_000)


def test_sem_and_confidence_interval_cover_the_true_mean_at_the_stated_rate():
    rng = np.random.default_rng(0)
    samples = rng.normal(3.0, 2.0, size=(2000, 10))
    covered = [lo <= 3.0 <= hi for _, lo, hi in map(stats.mean_ci, samples)]
    assert abs(np.mean(covered) - 0.95) < 0.02
    np.testing.assert_allclose(stats.sem(samples[0]), samples[0].std(ddof=1) / np.sqrt(10))


def test_r_and_the_t_tests_agree_with_scipy():
    """Each test's estimate, statistic and p against scipy's own: Pearson's r, the paired
    and the one-sample t (the statistic the Figure 5 protocols write)."""
    rng = np.random.default_rng(1)
    x = rng.normal(size=50)
    y = 0.6 * x + rng.normal(size=50)
    r, theirs = stats.fisher_r(x, y), scipy_stats.pearsonr(x, y)
    assert (r.estimate, r.p, r.dof) == pytest.approx((theirs.statistic, theirs.pvalue, 48))
    t, theirs = stats.paired(y, x), scipy_stats.ttest_rel(y, x)
    assert (t.statistic, t.p, t.dof) == pytest.approx((theirs.statistic, theirs.pvalue, 49))
    assert t.estimate == pytest.approx(np.mean(y - x))
    one, theirs = stats.one_sample(y, 0.25), scipy_stats.ttest_1samp(y, 0.25)
    assert (one.statistic, one.p, one.dof) == pytest.approx((theirs.statistic, theirs.pvalue, 49))


def test_stats_reject_bad_input():
    with pytest.raises(ValueError, match="same length"):
        stats.fisher_r([1, 2, 3, 4, 5], [1, 2, 3, 4])
    with pytest.raises(ValueError, match="at least 2"):
        stats.paired([1.0], [2.0])
    with pytest.raises(ValueError, match="level"):
        stats.mean_ci([1, 2, 3], level=1.5)


def test_the_slope_agrees_with_scipy_and_its_interval_covers_the_truth():
    """On y = 2 + 0.7 x + noise: the slope, its standard error and p are scipy's
    linregress; over many samples its 95 % interval covers 0.7 at about that rate."""
    rng = np.random.default_rng(11)
    x = np.repeat(np.log2([200.0, 800.0, 3200.0]), 3)
    covered = 0
    for _ in range(2000):
        y = 2 + 0.7 * x + rng.normal(0, 1, x.size)
        test = stats.slope(x, y)
        covered += test.low <= 0.7 <= test.high
    reference = scipy_stats.linregress(x, y)
    assert test.estimate == pytest.approx(reference.slope)
    assert test.p == pytest.approx(reference.pvalue)
    assert (test.high - test.low) / 2 == pytest.approx(
        scipy_stats.t.ppf(0.975, x.size - 2) * reference.stderr
    )
    assert 0.93 < covered / 2000 < 0.97
    with pytest.raises(ValueError, match="same length"):
        stats.slope([1.0, 2.0, 3.0], [1.0, 2.0])
