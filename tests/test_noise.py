"""The weight noise is standard normal, reproducible from its key and independent across
keys and neighbouring synapses."""

import jax
import numpy as np
import pytest
from scipy import special, stats

from sgb.noise import normal_from_bits, normal_quantile, standard_normal


def test_noise_is_standard_normal():
    z = np.asarray(standard_normal(jax.random.key(0), (1000, 1000))).ravel()
    n = z.size
    assert abs(z.mean()) < 4 / np.sqrt(n)
    assert abs(z.var() - 1.0) < 4 * np.sqrt(2 / n)
    assert abs(stats.skew(z)) < 4 * np.sqrt(6 / n)
    assert abs(stats.kurtosis(z)) < 4 * np.sqrt(24 / n)
    assert stats.kstest(z, "norm").pvalue > 1e-3
    # the tails are there: about 63 draws beyond 4 sigma are expected in a million
    assert 30 < np.sum(np.abs(z) > 4) < 110
    assert np.all(np.isfinite(z))


def test_same_key_same_noise_and_independent_streams():
    a = np.asarray(standard_normal(jax.random.key(1), (500, 400)))
    np.testing.assert_array_equal(a, np.asarray(standard_normal(jax.random.key(1), (500, 400))))
    limit = 4 / np.sqrt(a.size)
    for other in (jax.random.key(2), jax.random.split(jax.random.key(1))[0]):
        b = np.asarray(standard_normal(other, (500, 400)))
        assert abs(np.corrcoef(a.ravel(), b.ravel())[0, 1]) < limit
    flat = a.ravel()
    assert abs(np.corrcoef(flat[:-1], flat[1:])[0, 1]) < limit  # neighbouring synapses
    assert abs(np.corrcoef(a[:, :-1].ravel(), a[:, 1:].ravel())[0, 1]) < limit


def test_every_word_gives_a_finite_normal():
    extremes = np.array([0, 1, 511, 512, 2**31, 2**32 - 513, 2**32 - 512, 2**32 - 1], np.uint32)
    z = np.asarray(normal_from_bits(extremes))
    assert np.all(np.isfinite(z)) and np.all(np.abs(z) < 5.5)
    assert z[0] == -z[-1] and z[0] < -5  # symmetric, and the tails reach past 5 sigma


def test_normal_quantile_matches_scipy_on_every_tenth_grid_point():
    """Against scipy's float64 ndtri on the 23-bit grid the noise draws from, tails
    included."""
    u = ((np.arange(0, 2**23, 10) + 0.5) * 2.0**-23).astype(np.float32)
    got = np.asarray(normal_quantile(u), np.float64)
    want = special.ndtri(u.astype(np.float64))
    assert np.max(np.abs(got - want) / np.maximum(np.abs(want), 1e-2)) < 1e-6


def test_too_large_a_shape_is_refused():
    with pytest.raises(ValueError, match="2\\*\\*32"):
        standard_normal(jax.random.key(0), (2**16, 2**16))
