"""The moment-matched network (``sgb.moments``) against sampled individuals, its limit at
zero spread, and the mean-gap experiment's smoke run and figure."""

import jax
import jax.numpy as jnp
import matplotlib
import numpy as np
import pytest

from sgb import moments
from sgb.celltypes import expand_table
from sgb.data import load
from sgb.experiments import mean_gap
from sgb.genome import of_params, with_tables
from sgb.individuals import apply_mean_network, apply_population, init_params
from sgb.layers import SGBMLP
from sgb.provenance import read_results
from sgb.supervised_sweep import run_one

matplotlib.use("Agg")


def _within(estimate: np.ndarray, exact: np.ndarray, samples: np.ndarray, sds: float = 5.0):
    """``estimate`` (a Monte Carlo mean over axis 0 of ``samples``) within ``sds`` of its
    standard errors of ``exact`` (with 40,000 draws or more, 2.5 % of the draws' spread)."""
    se = samples.std(axis=0) / np.sqrt(len(samples))
    np.testing.assert_array_less(np.abs(estimate - exact), sds * se + 1e-9)


def _check_moments(draws: np.ndarray, mean: np.ndarray, var: np.ndarray) -> None:
    """Monte Carlo mean and variance of ``draws`` (N, ...) against ``mean`` and ``var``."""
    draws = np.asarray(draws, np.float64)
    _within(draws.mean(0), np.asarray(mean), draws)
    squares = (draws - draws.mean(0)) ** 2
    _within(squares.mean(0), np.asarray(var), squares)


@pytest.mark.parametrize("m", [-2.0, -0.3, 0.0, 0.5, 3.0])
@pytest.mark.parametrize("s", [0.1, 1.0, 2.5])
def test_relu_moments_match_monte_carlo(m, s):
    a = np.random.default_rng(0).normal(m, s, size=(400_000,))
    out = moments.relu_moments(jnp.float32(m), jnp.float32(s**2))
    _check_moments(np.maximum(a, 0.0)[:, None], out.mean[None], out.var[None])


def test_relu_moments_at_zero_variance_and_far_from_the_kink():
    m = jnp.array([-1.5, 0.0, 2.0])
    out = moments.relu_moments(m, jnp.zeros(3))
    np.testing.assert_array_equal(out.mean, [0.0, 0.0, 2.0])
    np.testing.assert_array_equal(out.var, [0.0, 0.0, 0.0])
    # z = +-1e4: the variance is s^2 above the kink and 0 below, with no cancellation
    far = moments.relu_moments(jnp.array([10.0, -10.0]), jnp.array([1e-6, 1e-6]))
    np.testing.assert_allclose(far.mean, [10.0, 0.0], rtol=1e-7)
    np.testing.assert_allclose(far.var, [1e-6, 0.0], rtol=1e-5, atol=1e-30)


def _noisy_params(model, x, seed: int, sigma: tuple[float, float] = (0.2, 0.9)):
    """Initial params of ``model`` with spreads drawn in ``sigma`` and random biases, so the
    hidden pre-activations straddle the ReLU's kink."""
    params = init_params(model, jax.random.key(seed), x[:1])
    rng = np.random.default_rng(seed)

    def noisy(path, leaf):
        name = path[-1].key
        if name == "rho":
            s = rng.uniform(*sigma, size=leaf.shape)
            return jnp.asarray(np.log(np.expm1(s)), jnp.float32)
        if name == "mu":
            return jnp.asarray(rng.normal(0.0, 0.6, size=leaf.shape), jnp.float32)
        return jnp.asarray(rng.normal(0.0, 0.5, size=leaf.shape), jnp.float32)

    return jax.tree_util.tree_map_with_path(noisy, params)


def _individuals(model, params, x, n: int) -> np.ndarray:
    return np.asarray(apply_population(model, params, x, jax.random.split(jax.random.key(7), n)))


def test_one_layer_moments_match_sampled_individuals():
    x = jnp.asarray(np.random.default_rng(1).normal(size=(5, 6)), jnp.float32)
    model = SGBMLP((4,), (3, 2), in_features=6)  # 6 inputs of 3 types, 4 outputs of 2
    params = _noisy_params(model, x, seed=1)
    out = moments.moment_logits(moments.mlp_layers(params), x)
    _check_moments(_individuals(model, params, x, 40_000), out.mean, out.var)


def test_one_layer_moments_of_random_independent_inputs():
    rng = np.random.default_rng(2)
    mu, sigma = rng.normal(size=(3, 2)), rng.uniform(0.2, 0.8, size=(3, 2))
    bias = rng.normal(size=4)
    m_x, v_x = rng.normal(size=(2, 6)), rng.uniform(0.1, 1.0, size=(2, 6))
    layer = moments.GaussianLayer(*(jnp.asarray(a, jnp.float32) for a in (mu, sigma, bias)))
    out = moments.dense_moments(
        moments.Moments(jnp.asarray(m_x, jnp.float32), jnp.asarray(v_x, jnp.float32)), layer
    )
    n = 100_000
    weights = np.asarray(expand_table(jnp.asarray(mu), (6, 4)))[None] + np.asarray(
        expand_table(jnp.asarray(sigma), (6, 4))
    )[None] * rng.normal(size=(n, 6, 4))
    inputs = m_x[None] + np.sqrt(v_x)[None] * rng.normal(size=(n, 2, 6))
    _check_moments(np.einsum("nbi,nij->nbj", inputs, weights) + bias, out.mean, out.var)


def test_two_layer_moments_match_sampled_individuals():
    x = jnp.asarray(np.random.default_rng(3).normal(size=(4, 5)), jnp.float32)
    model = SGBMLP((7, 3), (5, 4, 3), in_features=5)  # hidden 7 neurons of 4 types
    params = _noisy_params(model, x, seed=3)
    layers = moments.mlp_layers(params)
    out = moments.moment_logits(layers, x)
    _check_moments(_individuals(model, params, x, 40_000), out.mean, out.var)
    # the mean network differs from the individuals' average here, so the check has teeth
    plain = moments.moment_logits(moments.without_noise(layers), x).mean
    assert float(jnp.max(jnp.abs(plain - out.mean))) > 0.05


@pytest.mark.parametrize("rho", [-np.inf, -30.0])
def test_at_zero_spread_the_moment_network_is_the_mean_network(rho):
    data = load("digits")
    x, y = jnp.asarray(data.x_test), jnp.asarray(data.y_test)
    model = SGBMLP((16, 10), (8, 4, 10))
    params = _noisy_params(model, x, seed=4)
    params = jax.tree_util.tree_map_with_path(
        lambda path, leaf: jnp.full_like(leaf, rho) if path[-1].key == "rho" else leaf, params
    )
    out = jax.jit(moments.moment_logits)(moments.mlp_layers(params), x)
    mean_network = apply_mean_network(model, params, x)
    if rho == -np.inf:  # sigma exactly 0
        np.testing.assert_array_equal(out.var, 0.0)
    np.testing.assert_array_equal(out.mean, mean_network)
    accuracy = float((jnp.argmax(mean_network, -1) == y).mean())
    assert moments.moment_accuracy(params, x, y) == accuracy


def test_layer_statistics_weigh_type_pairs_by_their_synapses():
    model = SGBMLP((3,), (2, 1), in_features=5)  # input types of 3 and 2 neurons
    params = init_params(model, jax.random.key(0), jnp.zeros((1, 5)))
    tables = of_params(params)
    params = with_tables(
        params, {"SGBDense_0": tables["SGBDense_0"]._replace(mu=jnp.array([[1.0], [-4.0]]))}
    )
    (stats,) = moments.layer_statistics(params, 5)
    assert stats["shape"] == [5, 3] and stats["types"] == [2, 1]
    assert stats["mean_abs_mu"] == pytest.approx((3 * 1.0 + 2 * 4.0) / 5)
    assert stats["mean_sigma"] == pytest.approx(float(jax.nn.softplus(-5.0)), rel=1e-6)
    with pytest.raises(ValueError, match="SGBMLP"):
        moments.mlp_layers({"params": {"trunk": {}, "head": {}}})


def test_mean_gap_smoke_runs_end_to_end_and_resumes(tmp_path, monkeypatch):
    config = mean_gap.PROFILES["smoke"]
    path = mean_gap.run("smoke", tmp_path, progress=False)
    assert path.name == "mean_gap_digits_smoke.json"
    payload = read_results(path)
    assert payload["provenance"]["profile"] == "smoke"
    results = payload["results"]
    records = results["records"]
    assert len(records) == 3 and len(results["summary"]) == 3
    assert {r["rho_init"] for r in records} == {config.sweep.sgb.rho_init, -7.0}
    for r in records:
        assert len(r["individuals"]) == config.sweep.sgb.eval_individuals
        for key in mean_gap.METRICS:
            assert 0.0 <= r[key] <= 1.0
        assert r["sigma_start"] == pytest.approx(float(jax.nn.softplus(r["rho_init"])), rel=1e-5)
        assert len(r["layers"]) == 2 and len(r["hidden_activation"]) == 1
    # the fig2 cell at the sweep's own rho is Figure 2's run_one, individual for individual
    first = records[0]
    assert first["rho_init"] == config.sweep.sgb.rho_init
    data = load("digits")
    reference = run_one("sgb", first["setting"], first["seed"], data, config.sweep)
    assert first["individuals"] == reference["individuals"]
    assert first["mean_network"] == reference["mean_network"]

    def fail(*args, **kwargs):
        raise AssertionError("a finished cell was run again")

    monkeypatch.setattr(mean_gap, "run_cell", fail)
    assert read_results(mean_gap.run("smoke", tmp_path, progress=False))["results"] == results

    from sgb.plots import subplots
    from sgb.plots.mean_gap import plot_mean_gap

    _, ax = subplots()
    assert plot_mean_gap(mean_gap.MeanGap.model_validate(payload).results, ax=ax) is ax
    assert len(ax.containers) == 3 * 2  # a bar container and an error bar per series
