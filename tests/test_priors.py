import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, stats

from sgb.priors import GaussianPrior, ScaleMixturePrior


def test_gaussian_kl_closed_form_matches_monte_carlo():
    prior = GaussianPrior(0.3)
    mu, sigma = jnp.array([0.5, -0.2, 0.0]), jnp.array([0.1, 0.4, 0.3])
    n = 400_000
    eps = jax.random.normal(jax.random.key(0), (n, 3))
    w = mu + sigma * eps
    mc_terms = ScaleMixturePrior(1.0, 0.3, 1.0).kl(mu, sigma, w)  # pi=1: the same Gaussian
    mc = mc_terms.mean(axis=0)
    se = mc_terms.std(axis=0) / np.sqrt(n)
    closed = prior.kl(mu, sigma)
    assert np.all(np.abs(mc - closed) < 4 * se + 1e-6)
    assert float(prior.kl(jnp.array(0.0), jnp.array(0.3))) == pytest.approx(0.0, abs=1e-6)


def test_scale_mixture_log_density_matches_direct_computation():
    prior = ScaleMixturePrior(pi=0.25, sigma1=1.5, sigma2=0.05)
    w = np.linspace(-4, 4, 41)
    direct = np.log(0.25 * stats.norm.pdf(w, 0, 1.5) + 0.75 * stats.norm.pdf(w, 0, 0.05))
    np.testing.assert_allclose(np.asarray(prior.log_prob(jnp.asarray(w))), direct, rtol=1e-5)
    total, _ = integrate.quad(lambda v: float(np.exp(prior.log_prob(jnp.asarray(v)))), -20, 20)
    assert total == pytest.approx(1.0, abs=1e-4)


def test_scale_mixture_kl_needs_a_sample():
    with pytest.raises(ValueError, match="sample w"):
        ScaleMixturePrior().kl(jnp.zeros(2), jnp.ones(2))


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: GaussianPrior(0.0), "sigma"),
        (lambda: GaussianPrior(-1.0), "sigma"),
        (lambda: ScaleMixturePrior(pi=1.5), "pi"),
        (lambda: ScaleMixturePrior(pi=-0.1), "pi"),
        (lambda: ScaleMixturePrior(sigma2=0.0), "sigma2"),
    ],
)
def test_bad_prior_parameters_raise(make, match):
    with pytest.raises(ValueError, match=match):
        make()
