import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, stats

from sgb import genome
from sgb.celltypes import assign_cell_types, block_counts, expand_table, sum_blocks, type_pair_block
from sgb.compression import tree_param_count
from sgb.elbo import elbo_loss, sown_kl
from sgb.genome import LayerGenome, individual_kernel, layer_kl, of_params, with_tables
from sgb.individuals import (
    apply_mean_network,
    apply_population,
    individual_kernels,
    init_params,
)
from sgb.layers import (
    SGBMLP,
    SGBConv,
    SGBDense,
    individual_matmul,
)
from sgb.priors import GaussianPrior, ScaleMixturePrior
from sgb.rl.agent import MLP, NetworkConfig, forward, make_agent


def _init(model, x, seed=0):
    return init_params(model, jax.random.key(seed), x)


def test_sampled_weights_of_a_type_pair_have_the_tables_mean_and_sigma():
    layer = SGBDense(120, in_types=3, out_types=4)
    x = jnp.ones((1, 90))
    params = _init(layer, x)
    mu, rho = of_params(params)[""]  # a lone layer's genome sits at the root
    mu, rho = mu.at[1, 2].set(0.7), rho.at[1, 2].set(jnp.log(jnp.expm1(0.25)))  # sigma = 0.25
    params = with_tables(params, {"": LayerGenome(mu, rho)})
    kernel = individual_kernels(layer, params, x, jax.random.key(3))[""]
    block = np.asarray(type_pair_block(kernel, (3, 4), (1, 2))).ravel()
    assert block.size == 30 * 30
    n = block.size
    assert abs(block.mean() - 0.7) < 4 * 0.25 / np.sqrt(n)
    # the sample std of n normals has standard error sigma / sqrt(2(n-1))
    assert abs(block.std(ddof=1) - 0.25) < 4 * 0.25 / np.sqrt(2 * (n - 1))


def test_full_bnn_limit_has_independent_parameters_per_synapse():
    layer = SGBDense(7, in_types=None, out_types=None)
    params = _init(layer, jnp.ones((1, 5)))
    genome = of_params(params)[""]
    assert genome.mu.shape == (5, 7) and genome.rho.shape == (5, 7)
    assert tree_param_count(params) == 2 * 5 * 7 + 7
    mean_kernel = individual_kernels(layer, params, jnp.ones((1, 5)), None)[""]
    np.testing.assert_array_equal(mean_kernel, genome.mu)
    one_type = _init(SGBDense(7, in_types=1, out_types=1), jnp.ones((1, 5)))
    assert tree_param_count(one_type) == 2 + 7


@pytest.mark.parametrize("individuals", [(), (3,), (2, 5)])
def test_individual_kernel_gradient_matches_autodiff_of_its_formula(individuals):
    """The hand-written backward pass (noise taken back from the kernel, summed over any
    leading axes of individuals) against JAX's autodiff of mu + softplus(rho) * noise,
    with uneven type blocks and rho from -30 to 2."""
    key_mu, key_rho, key_noise, key_x = jax.random.split(jax.random.key(0), 4)
    mu = 0.1 * jax.random.normal(key_mu, (3, 4))
    rho = jax.random.uniform(key_rho, (3, 4), minval=-8.0, maxval=2.0).at[0, 0].set(-30.0)
    noise = jax.random.normal(key_noise, (*individuals, 10, 11))
    x = jax.random.normal(key_x, (*individuals, 5, 10))

    def plain(mu, rho, noise):
        sigma = jax.nn.softplus(rho)
        return expand_table(mu, (10, 11)) + expand_table(sigma, (10, 11)) * noise

    def loss(kernel_fn, mu, rho, noise):
        return jnp.sum(jnp.tanh(x @ kernel_fn(mu, rho, noise)) ** 2)

    ours = jax.grad(loss, argnums=(1, 2, 3))(individual_kernel, mu, rho, noise)
    reference = jax.grad(loss, argnums=(1, 2, 3))(plain, mu, rho, noise)
    np.testing.assert_allclose(individual_kernel(mu, rho, noise), plain(mu, rho, noise), rtol=1e-6)
    for got, want in zip(ours, reference, strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(
        sum_blocks(jnp.ones((10, 11)), (3, 4)), block_counts((10, 11), (3, 4))
    )


@pytest.mark.parametrize("rows", [(), (6,), (2, 3)])
def test_individual_matmul_and_its_gradient_match_the_plain_batched_product(rows):
    """Row n of the inputs through kernel n, with none, one and two axes of rows per
    individual: values and both gradients against autodiff of the einsum."""
    key_x, key_k, key_w = jax.random.split(jax.random.key(1), 3)
    x = jax.random.normal(key_x, (4, *rows, 9))
    kernels = jax.random.normal(key_k, (4, 9, 7))
    weights = jax.random.normal(key_w, (4, *rows, 7))

    def plain(x, kernels):
        return jnp.stack([x[n] @ kernels[n] for n in range(4)])

    def loss(matmul, x, kernels):
        return jnp.sum(jnp.tanh(matmul(x, kernels)) * weights)

    np.testing.assert_allclose(individual_matmul(x, kernels), plain(x, kernels), rtol=1e-5)
    ours = jax.jit(jax.grad(loss, argnums=(1, 2)), static_argnums=0)(individual_matmul, x, kernels)
    reference = jax.grad(loss, argnums=(1, 2))(plain, x, kernels)
    for got, want in zip(ours, reference, strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)


def test_population_vmap_gives_distinct_individuals_and_keys_are_reproducible():
    model = SGBMLP(widths=(16, 3), cell_types=(2, 4, 3))
    x = jax.random.normal(jax.random.key(1), (8, 6))
    params = _init(model, x)
    keys = jax.random.split(jax.random.key(2), 100)
    outputs = np.asarray(apply_population(model, params, x, keys))
    assert outputs.shape == (100, 8, 3)
    flat = outputs.reshape(100, -1)
    distances = np.linalg.norm(flat[:, None] - flat[None], axis=-1)
    assert np.all(distances[~np.eye(100, dtype=bool)] > 0)
    again = np.asarray(apply_population(model, params, x, keys[:5]))
    np.testing.assert_array_equal(again, outputs[:5])
    single = np.asarray(model.apply(params, x, rngs={"sample": keys[7]}))
    np.testing.assert_allclose(single, outputs[7], rtol=1e-5, atol=1e-6)


def test_mean_network_makes_neurons_of_a_type_identical():
    model = SGBMLP(widths=(12, 2), cell_types=(None, 3, 2))
    x = jax.random.normal(jax.random.key(0), (4, 5))
    params = _init(model, x)
    _, hidden = model.apply(
        params, x, mean_network=True, capture_intermediates=True, mutable=["intermediates"]
    )
    pre = np.asarray(hidden["intermediates"]["SGBDense_0"]["__call__"][0])
    for t in range(3):
        block = pre[:, assign_cell_types(12, 3) == t]
        np.testing.assert_allclose(block, block[:, :1].repeat(block.shape[1], 1), atol=1e-6)
    np.testing.assert_allclose(
        apply_mean_network(model, params, x),
        model.apply(params, x, mean_network=True),
        rtol=1e-5,
        atol=1e-6,
    )


@pytest.mark.parametrize("prior", [GaussianPrior(0.2), ScaleMixturePrior(0.5, 0.5, 0.01)])
def test_layer_kl_counts_synapses_and_is_unbiased(prior):
    """Per synapse = block size x per pair; averaged over keys, the mixture's one-draw
    estimate per pair equals the KL integrated numerically (the Gaussian's is exact)."""
    mu = jnp.array([[0.1, -0.3]])
    sigma = jnp.array([[0.05, 0.1]])
    shape = (4, 6)  # one input type of 4 neurons, two output types of 3: 12 synapses per pair
    key = jax.random.key(3)
    synapse = layer_kl(prior, mu, sigma, shape, "synapse", key)
    table = layer_kl(prior, mu, sigma, shape, "table", key)
    assert float(synapse) == pytest.approx(12 * float(table), rel=1e-5)

    def pair_kl(m: float, s: float) -> float:
        def integrand(w: float) -> float:
            log_q = stats.norm.logpdf(w, m, s)
            return np.exp(log_q) * (log_q - float(prior.log_prob(jnp.asarray(w))))

        return integrate.quad(integrand, m - 10 * s, m + 10 * s, points=[0.0], limit=200)[0]

    exact = sum(pair_kl(float(m), float(s)) for m, s in zip(mu[0], sigma[0], strict=True))
    keys = jax.random.split(jax.random.key(4), 20_000)
    draws = np.asarray(
        jax.jit(jax.vmap(lambda k: layer_kl(prior, mu, sigma, shape, "table", k)))(keys)
    )
    assert abs(draws.mean() - exact) < 4 * draws.std() / np.sqrt(len(draws)) + 1e-5


def test_elbo_averages_the_data_term_over_samples():
    model = SGBMLP(widths=(8, 3), cell_types=(2, 2, 3), prior=ScaleMixturePrior())
    x = jax.random.normal(jax.random.key(0), (10, 4))
    y = jnp.arange(10) % 3
    params = _init(model, x)
    key = jax.random.key(5)
    loss, parts = elbo_loss(model, params, x, y, key, num_samples=4, kl_weight=0.01)
    datas, kls = [], []
    for k in jax.random.split(key, 4):
        logits, state = model.apply(params, x, rngs={"sample": k}, mutable=["losses"])
        datas.append(-jax.nn.log_softmax(logits)[jnp.arange(10), y].mean())
        kls.append(sown_kl(state))
    assert float(parts["data"]) == pytest.approx(float(np.mean(datas)), rel=1e-5)
    assert float(parts["kl"]) == pytest.approx(float(np.mean(kls)), rel=1e-5)
    assert float(loss) == pytest.approx(np.mean(datas) + 0.01 * np.mean(kls), rel=1e-5)
    assert len({round(float(d), 6) for d in datas}) == 4


def test_conv_layer_kernel_follows_its_four_d_genome():
    layer = SGBConv(features=6, kernel_size=(3, 3), types=(1, 3, 2, 3))
    x = jnp.ones((1, 5, 5, 4))
    params = _init(layer, x)
    assert of_params(params)[""].mu.shape == (1, 3, 2, 3)
    y = layer.apply(params, x, rngs={"sample": jax.random.key(0)})
    assert y.shape == (1, 5, 5, 6)
    kernel = individual_kernels(layer, params, x, None)[""]
    assert kernel.shape == (3, 3, 4, 6)
    np.testing.assert_array_equal(kernel[0], kernel[2])  # one height type: rows share means


@pytest.mark.parametrize(
    ("make", "shape", "match"),
    [
        (lambda: SGBDense(4, in_types=6), (1, 5), "in_types"),
        (lambda: SGBDense(4, out_types=5), (1, 5), "out_types"),
        (lambda: SGBDense(4, out_types=0), (1, 5), "out_types"),
        (lambda: SGBMLP(widths=(4, 2), cell_types=(1, 1)), (1, 5), "cell_types"),
        (lambda: SGBConv(4, (3, 3), types=(4, 1, 1, 1)), (1, 5, 5, 2), "height types"),
    ],
)
def test_bad_layer_arguments_raise_clear_errors(make, shape, match):
    with pytest.raises(ValueError, match=match):
        _init(make(), jnp.ones(shape))


def test_elbo_rejects_zero_samples():
    model = SGBMLP(widths=(3,), cell_types=(None, None))
    params = _init(model, jnp.ones((1, 2)))
    with pytest.raises(ValueError, match="num_samples"):
        elbo_loss(
            model,
            params,
            jnp.ones((1, 2)),
            jnp.zeros(1, int),
            jax.random.key(0),
            num_samples=0,
            kl_weight=1.0,
        )


def _sown(model, params, x, key):
    """The output and what the layers sowed, applied with ``rngs={"sample": key}``."""
    out, state = jax.jit(
        lambda k: model.apply(params, x, rngs={"sample": k}, mutable=["individual", "losses"])
    )(key)
    return (
        out,
        genome.sown(state["individual"], "noise"),
        genome.sown(state["individual"], "kernel"),
        genome.sown(state["losses"], "kl"),
    )


@pytest.mark.parametrize("make_key", [jax.random.key, jax.random.PRNGKey])
def test_one_key_gives_one_individual_in_the_flax_layers_and_the_pure_functions(make_key):
    """A 3-layer SGBMLP applied with ``rngs={"sample": key}`` draws bit for bit the noise,
    kernels and per-layer Monte Carlo KLs (scale mixture prior) that ``draw_noise``,
    ``kernels`` and ``kl`` give for the same key; two layers of one shape draw apart."""
    model = SGBMLP(
        (8, 8, 3), (None, 4, 4, None), prior=ScaleMixturePrior(), rho_init=-1.0, in_features=8
    )
    x = jax.random.normal(jax.random.key(0), (5, 8))
    params = _init(model, x)
    tables = of_params(params)
    shapes = {"SGBDense_0": (8, 8), "SGBDense_1": (8, 8), "SGBDense_2": (8, 3)}
    assert list(tables) == list(shapes)
    seen = []
    for seed in (1, 2):
        key = make_key(seed)
        out, noise, kernels, kls = _sown(model, params, x, key)
        drawn = jax.jit(lambda k: genome.draw_noise(k, shapes))(key)
        developed = jax.jit(genome.kernels)(tables, drawn)
        assert list(noise) == list(kernels) == list(kls) == list(shapes)
        for i, name in enumerate(shapes):
            np.testing.assert_array_equal(noise[name], drawn[name])
            np.testing.assert_array_equal(kernels[name], developed[name])
            kl = layer_kl(
                ScaleMixturePrior(),
                tables[name].mu,
                genome.sigma(tables[name]),
                shapes[name],
                "synapse",
                genome.layer_key(genome.kl_key(key), i),
            )
            np.testing.assert_array_equal(kls[name], kl)
        total = genome.kl(tables, shapes, ScaleMixturePrior(), genome.kl_key(key))
        np.testing.assert_allclose(sum(kls.values()), total, rtol=1e-6)
        h = x
        for i, name in enumerate(shapes):
            h = h @ developed[name] + params["params"][name]["bias"]
            h = jax.nn.relu(h) if i < 2 else h
        np.testing.assert_allclose(out, h, rtol=1e-5, atol=1e-6)
        assert not np.array_equal(noise["SGBDense_0"], noise["SGBDense_1"])
        seen.append(noise["SGBDense_0"])
    assert not np.array_equal(*seen)


def test_the_agents_flax_network_draws_the_individual_born_from_its_key():
    """The RL actor's Flax definition (SGB output layer, Bayesian biases) applied with an
    individual's key develops bit for bit the kernels and biases of ``Network.draw`` and
    ``Network.layers``, and gives ``forward``'s output."""
    network = NetworkConfig(
        hidden=(16, 8),
        cell_types=4,
        rho_init=-1.0,
        typed_inputs=True,
        sgb_output=True,
        bayesian_biases=True,
    )
    actor = make_agent(network, 5, 2).actor
    params = actor.init(jax.random.PRNGKey(0), network)
    assert len(actor.sgb_shapes) == 6
    x = jax.random.normal(jax.random.key(1), (3, 5))
    key = jax.random.PRNGKey(7)
    out, noise, kernels, _ = _sown(MLP(network, 4, 5), params, x, key)
    drawn = jax.jit(actor.draw)(key)
    layers = jax.jit(actor.layers)(params, drawn)
    assert sorted(noise) == sorted(drawn)
    for name in drawn:
        np.testing.assert_array_equal(noise[name], drawn[name])
    for name, (kernel, bias) in zip(actor.names, layers, strict=True):
        np.testing.assert_array_equal(kernels[name], kernel)
        np.testing.assert_array_equal(kernels[f"{name}/bias"][0], bias)
    np.testing.assert_allclose(out, forward(layers, x), rtol=1e-5, atol=1e-6)
