"""The genome's pure functions: reading and writing Flax parameters, the one draw of
individuals and its statistics, and the KL summed over layers."""

import jax
import jax.numpy as jnp
import numpy as np

from sgb import genome
from sgb.celltypes import expand_table
from sgb.individuals import individual_kernels, init_params
from sgb.layers import SGBMLP
from sgb.priors import GaussianPrior

SHAPES = {"SGBDense_0": (12, 8), "SGBDense_1": (8, 4)}


def _params():
    model = SGBMLP((8, 4), (3, 2, None), rho_init=-1.0, in_features=12)
    return model, init_params(model, jax.random.key(0), jnp.zeros((1, 12)))


def test_tables_written_back_are_read_back_and_nothing_else_changes():
    model, params = _params()
    tables = genome.of_params(params)
    assert list(tables) == list(SHAPES)
    assert tables["SGBDense_0"].mu.shape == (3, 2) and tables["SGBDense_1"].mu.shape == (2, 4)
    moved = {name: genome.LayerGenome(g.mu + 1.0, g.rho - 1.0) for name, g in tables.items()}
    written = genome.with_tables(params, moved)
    for name, g in genome.of_params(written).items():
        np.testing.assert_array_equal(g.mu, moved[name].mu)
        np.testing.assert_array_equal(g.rho, moved[name].rho)
    np.testing.assert_array_equal(
        written["params"]["SGBDense_1"]["bias"], params["params"]["SGBDense_1"]["bias"]
    )
    np.testing.assert_array_equal(
        genome.of_params(params)["SGBDense_0"].mu, tables["SGBDense_0"].mu
    )


def test_the_layers_develop_the_genomes_mean_network():
    model, params = _params()
    mean = individual_kernels(model, params, jnp.zeros((1, 12)), None)
    expected = genome.mean_kernels(genome.of_params(params), SHAPES)
    for name in SHAPES:
        np.testing.assert_array_equal(mean[name], expected[name])


def test_individuals_have_their_type_pairs_moments_and_independent_layers():
    """5,000 individuals of a two-layer genome: each synapse has its pair's mean and
    spread; one key always gives the same individual; the layers' noise is uncorrelated."""
    _, params = _params()
    tables = genome.of_params(params)
    keys = jax.random.split(jax.random.key(1), 5000)
    noise = jax.vmap(lambda k: genome.draw_noise(k, SHAPES))(keys)
    again = genome.draw_noise(keys[7], SHAPES)
    for name in SHAPES:
        np.testing.assert_array_equal(noise[name][7], again[name])
    kernels = genome.kernels(tables, noise)
    n = len(keys)
    for name, shape in SHAPES.items():
        mean = expand_table(tables[name].mu, shape)
        spread = expand_table(genome.sigma(tables[name]), shape)
        z = (np.asarray(kernels[name].mean(axis=0)) - mean) / (spread / np.sqrt(n))
        assert np.abs(z).max() < 5.0  # 96 and 32 synapses, each within 5 standard errors
        ratio = np.asarray(kernels[name].std(axis=0)) / spread
        assert np.abs(ratio - 1.0).max() < 5.0 / np.sqrt(2 * (n - 1))
    r = np.corrcoef(
        np.asarray(noise["SGBDense_0"][:, 0, 0]), np.asarray(noise["SGBDense_1"][:, 0, 0])
    )
    assert abs(r[0, 1]) < 4.0 / np.sqrt(n)


def test_the_kl_of_a_genome_is_the_sum_of_its_layers_and_matches_monte_carlo():
    """Gaussian prior, closed form: the genome's KL is the layers' summed, and equals a
    Monte Carlo average of log q(w) - log p(w) over drawn individuals."""
    _, params = _params()
    tables = genome.of_params(params)
    prior = GaussianPrior(0.1)
    key = jax.random.key(2)
    total = genome.kl(tables, SHAPES, prior, key)
    layers = sum(
        genome.layer_kl(prior, g.mu, genome.sigma(g), SHAPES[name], "synapse", key)
        for name, g in tables.items()
    )
    np.testing.assert_allclose(total, layers, rtol=1e-6)
    keys = jax.random.split(jax.random.key(3), 4000)

    def log_ratio(k):
        noise = genome.draw_noise(k, SHAPES)
        kernels = genome.kernels(tables, noise)
        out = 0.0
        for name, shape in SHAPES.items():
            mean = expand_table(tables[name].mu, shape)
            sigma = expand_table(genome.sigma(tables[name]), shape)
            w = kernels[name]
            log_q = -0.5 * ((w - mean) / sigma) ** 2 - jnp.log(sigma)
            log_p = -0.5 * (w / prior.sigma) ** 2 - jnp.log(prior.sigma)
            out = out + jnp.sum(log_q - log_p)
        return out

    draws = np.asarray(jax.jit(jax.vmap(log_ratio))(keys))
    se = draws.std() / np.sqrt(len(draws))
    assert abs(draws.mean() - float(total)) < 4 * se


def test_an_individuals_layer_keys_are_the_splits_the_rl_births_were_drawn_with():
    """``layer_key(key, i)`` is ``split(key, n)[i]`` for any n > i, so ``draw_noise`` and
    ``kl`` draw exactly what they drew with ``split(key, len(shapes))`` (the committed RL
    results' births and KLs), for raw and typed keys alike; the KL's key is neither."""
    shapes = {"a": (5, 3), "a/bias": (1, 3), "b": (3, 3), "out": (3, 2)}
    for key in (jax.random.PRNGKey(11), jax.random.key(12)):
        for n in (4, 5, 9):
            for i, k in enumerate(jax.random.split(key, n)[:4]):
                np.testing.assert_array_equal(
                    jax.random.key_data(genome.layer_key(key, i)), jax.random.key_data(k)
                )
        old = jax.random.split(key, len(shapes))
        noise = genome.draw_noise(key, shapes)
        for (name, shape), k in zip(shapes.items(), old, strict=True):
            np.testing.assert_array_equal(noise[name], genome.draw_layer_noise(k, shape))
        layers = [genome.layer_key(key, i) for i in range(len(shapes))]
        kl = jax.random.key_data(genome.kl_key(key))
        assert all((kl != jax.random.key_data(k)).any() for k in [key, *layers])
