"""``sgb.reliability``: the variance split recovers a known intraclass correlation, and the
detectable SD between individuals is found at the stated power."""

import numpy as np
import pytest

from sgb.reliability import (
    between_sd_at,
    detectable_between_sd,
    episodes_for,
    episodes_to_detect,
    projected_reliability,
    variance_split,
)


def test_variance_split_recovers_a_known_intraclass_correlation():
    rng = np.random.default_rng(5)
    sigma_b, sigma_w, n, k = 1.0, 2.0, 200, 5
    icc = sigma_b**2 / (sigma_b**2 + sigma_w**2)  # 0.2
    covered = 0
    for _ in range(200):
        x = rng.normal(0, sigma_b, (n, 1)) + rng.normal(0, sigma_w, (n, k))
        split = variance_split(x)
        covered += split.icc_ci[0] <= icc <= split.icc_ci[1]
    assert 0.91 <= covered / 200 <= 0.99
    assert split.reliability == pytest.approx(projected_reliability(split.icc, k), rel=1e-9)
    assert episodes_for(0.2) == pytest.approx(16.0)
    assert projected_reliability(0.2, episodes_for(0.2)) == pytest.approx(0.8)
    # individuals that do not differ: the split says so
    same = variance_split(rng.normal(0, 1, (100, 3)))
    assert same.icc_ci[0] < 0 < same.icc_ci[1]


def test_the_detectable_between_sd_is_found_four_times_in_five():
    """At the SD between individuals it names, the F-test (p < 0.05) rejects in about 80 %
    of simulated populations (30 individuals x 5 episodes, within SD 1), and more episodes
    lower it to any target."""
    rng = np.random.default_rng(3)
    n, k = 30, 5
    sd = detectable_between_sd(n, k, 1.0)
    found = 0
    for _ in range(3000):
        x = rng.normal(0, sd, (n, 1)) + rng.normal(0, 1.0, (n, k))
        found += variance_split(x).p < 0.05
    assert abs(found / 3000 - 0.8) < 0.03
    k_needed = episodes_to_detect(n, 1.0, sd / 2)
    assert detectable_between_sd(n, k_needed, 1.0) <= sd / 2
    assert detectable_between_sd(n, k_needed - 1, 1.0) > sd / 2
    assert between_sd_at(0.2, 4.0) == pytest.approx(1.0)
    assert between_sd_at(-0.01, 4.0) == 0.0


def test_a_crossed_split_takes_out_the_shared_parts_and_keeps_its_coverage():
    """Every individual scored on the same 10 parts, whose difficulty (SD 3) dwarfs the
    individuals' (SD 0.5) and the residual (SD 1): crossed, the split recovers the ICC
    0.2 with its stated coverage; one-way, the parts' spread drowns the individuals."""
    rng = np.random.default_rng(6)
    sigma_b, sigma_w, n, k = 0.5, 1.0, 100, 10
    icc = sigma_b**2 / (sigma_b**2 + sigma_w**2)
    covered = 0
    for _ in range(200):
        parts = rng.normal(0, 3.0, (1, k))
        x = parts + rng.normal(0, sigma_b, (n, 1)) + rng.normal(0, sigma_w, (n, k))
        split = variance_split(x, crossed=True)
        covered += split.icc_ci[0] <= icc <= split.icc_ci[1]
    assert 0.91 <= covered / 200 <= 0.99
    assert split.within_var == pytest.approx(sigma_w**2, rel=0.15)
    assert variance_split(x).icc < 0.05 < split.icc
