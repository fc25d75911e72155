"""The local reparameterisation: exact pre-activation moments, and the same expected ELBO."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from sgb.celltypes import expand_table
from sgb.elbo import cross_entropy, sown_kl
from sgb.genome import LayerGenome, of_params, with_tables
from sgb.genome import sigma as layer_sigma
from sgb.individuals import apply_mean_network, init_params
from sgb.layers import SGBMLP, SGBDense, type_matmul
from sgb.priors import GaussianPrior, ScaleMixturePrior

KEYS = jax.random.split(jax.random.key(7), 4000)


def _spread_out(params, seed=0):
    """Give every type pair a different, appreciable sigma (0.1 to 0.6) and nonzero mean."""
    rng = np.random.default_rng(seed)

    def spread(g: LayerGenome) -> LayerGenome:
        sigma = rng.uniform(0.1, 0.6, g.rho.shape)
        rho = jnp.asarray(np.log(np.expm1(sigma)), jnp.float32)
        return LayerGenome(jnp.asarray(rng.normal(0.0, 0.5, g.mu.shape), jnp.float32), rho)

    return with_tables(params, {name: spread(g) for name, g in of_params(params).items()})


@pytest.mark.parametrize(
    ("n_in", "features", "k_in", "k_out"), [(7, 5, 3, 2), (10, 6, 10, 6), (9, 11, 1, 4)]
)
def test_type_matmul_equals_the_expanded_matrix_product(n_in, features, k_in, k_out):
    x = jax.random.normal(jax.random.key(0), (2, 3, n_in))
    table = jax.random.normal(jax.random.key(1), (k_in, k_out))
    expected = x @ expand_table(table, (n_in, features))
    np.testing.assert_allclose(type_matmul(x, table, features), expected, rtol=1e-5, atol=1e-5)


def test_local_preactivations_have_the_exact_mean_and_variance():
    layer = SGBDense(5, in_types=3, out_types=2)
    x = jax.random.normal(jax.random.key(0), (4, 7))
    params = _spread_out(init_params(layer, jax.random.key(1), x))
    genome = of_params(params)[""]
    mu = expand_table(genome.mu, (7, 5))
    sigma = expand_table(layer_sigma(genome), (7, 5))
    mean, var = np.asarray(x @ mu), np.asarray(x**2 @ sigma**2)

    def draw(key):
        return layer.apply(params, x, rngs={"sample": key}, local_reparam=True)

    y = np.asarray(jax.jit(jax.vmap(draw))(KEYS))
    n = len(KEYS)
    assert np.all(np.abs(y.mean(0) - mean) < 4 * np.sqrt(var / n))
    # the sample variance of n normals has standard error var * sqrt(2 / (n - 1))
    assert np.all(np.abs(y.var(0, ddof=1) - var) < 4 * var * np.sqrt(2 / (n - 1)))
    # the mean network is the same on both paths
    np.testing.assert_allclose(
        layer.apply(params, x, mean_network=True, local_reparam=True),
        layer.apply(params, x, mean_network=True),
        rtol=1e-5,
        atol=1e-6,
    )


def test_both_estimators_give_the_same_expected_loss_of_a_two_layer_network():
    model = SGBMLP(widths=(6, 3), cell_types=(4, 3, 3))
    x = jax.random.normal(jax.random.key(2), (16, 8))
    labels = jnp.arange(16) % 3
    params = _spread_out(init_params(model, jax.random.key(3), x), seed=1)

    def losses(local):
        def one(key):
            logits = model.apply(params, x, rngs={"sample": key}, local_reparam=local)
            return cross_entropy(logits, labels)

        values = np.asarray(jax.jit(jax.vmap(one))(KEYS))
        return values.mean(), values.std(ddof=1) / np.sqrt(len(values))

    (shared, se_shared), (local, se_local) = losses(False), losses(True)
    assert abs(shared - local) < 4 * np.hypot(se_shared, se_local)
    # the noise matters: the population's loss is far from the mean network's
    mean_loss = float(cross_entropy(apply_mean_network(model, params, x), labels))
    assert abs(shared - mean_loss) > 10 * se_shared
    # and per-example noise has the lower variance
    assert se_local < se_shared


@pytest.mark.parametrize("counting", ["synapse", "table"])
@pytest.mark.parametrize("prior", [GaussianPrior(0.3), ScaleMixturePrior(0.5, 1.0, 0.05)])
def test_local_kl_estimates_the_same_kl(prior, counting):
    layer = SGBDense(6, in_types=2, out_types=3, prior=prior, kl_counting=counting)
    x = jnp.ones((1, 5))
    params = _spread_out(init_params(layer, jax.random.key(0), x))

    def kl(local):
        def one(key):
            _, state = layer.apply(
                params, x, rngs={"sample": key}, mutable=["losses"], local_reparam=local
            )
            return sown_kl(state)

        values = np.asarray(jax.jit(jax.vmap(one))(KEYS))
        return values.mean(), values.std(ddof=1) / np.sqrt(len(values))

    (shared, se_shared), (local, se_local) = kl(False), kl(True)
    if isinstance(prior, GaussianPrior):  # closed form on both paths
        np.testing.assert_allclose(local, shared, rtol=1e-5)
        assert se_local < 1e-4 * abs(local)
    else:
        assert abs(shared - local) < 4 * np.hypot(se_shared, se_local)
