"""Tests of sgb.theory: the Jensen gap, its second-order predictions, the (mu, sigma) step."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from sgb import theory
from sgb.experiments import theory as experiment
from sgb.population import individual_kernels
from sgb.provenance import read_results
from sgb.supervised import ClassifierConfig, make_model


def _quadratic(seed: int, size: int = 6, diagonal: bool = False):
    """L(w) = 1/2 w^T A w + b^T w with a random symmetric, indefinite A; and mu, sigma."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(size, size))
    a = np.diag(rng.normal(size=size)) if diagonal else (a + a.T) / 2
    b = rng.normal(size=size)
    a, b = jnp.asarray(a, jnp.float32), jnp.asarray(b, jnp.float32)
    mu = jnp.asarray(rng.normal(size=size), jnp.float32)
    sigma = jnp.asarray(rng.uniform(0.2, 1.0, size=size), jnp.float32)
    return (lambda w: 0.5 * w @ a @ w + b @ w), a, mu, sigma


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_quadratic_gap_matches_half_weighted_diagonal(seed):
    loss, a, mu, sigma = _quadratic(seed)
    assert jnp.linalg.eigvalsh(a).min() < 0 < jnp.linalg.eigvalsh(a).max()  # indefinite
    expected = 0.5 * jnp.sum(sigma**2 * jnp.diag(a))
    gap = theory.jensen_gap(loss, mu, sigma, jax.random.key(seed), num_samples=4000)
    assert abs(gap.gap - expected) < 3 * gap.stderr
    assert gap.stderr > 0
    assert jnp.isclose(gap.mean_network_loss, loss(mu))


def test_gap_accepts_pytrees_and_plain_sampling():
    loss, _, mu, sigma = _quadratic(3)
    tree_loss = lambda w: loss(jnp.concatenate([w["a"], w["b"]]))  # noqa: E731
    split = lambda v: {"a": v[:2], "b": v[2:]}  # noqa: E731
    expected = theory.second_order_eigen(loss, mu, sigma).gap
    for antithetic in (True, False):
        gap = theory.jensen_gap(
            tree_loss, split(mu), split(sigma), jax.random.key(5), 4000, antithetic=antithetic
        )
        assert abs(gap.gap - expected) < 3 * gap.stderr


@pytest.mark.parametrize("seed", [0, 1])
def test_eigen_and_trace_forms_agree(seed):
    loss, a, mu, sigma = _quadratic(seed, size=9)
    eigen = theory.second_order_eigen(loss, mu, sigma)
    exact = theory.second_order_trace(loss, mu, sigma, chunk_size=4)  # chunks not dividing P
    np.testing.assert_allclose(eigen.gap, exact.value, rtol=1e-5)
    np.testing.assert_allclose(eigen.gap, 0.5 * jnp.sum(sigma**2 * jnp.diag(a)), rtol=1e-5)
    np.testing.assert_allclose(eigen.rho2.sum(), jnp.sum(sigma**2), rtol=1e-5)
    assert exact.stderr == 0


def test_hutchinson_trace_is_unbiased():
    loss, _, mu, sigma = _quadratic(4, size=9)
    exact = theory.second_order_trace(loss, mu, sigma).value
    estimate = theory.second_order_trace(loss, mu, sigma, jax.random.key(0), num_probes=2000)
    assert abs(estimate.value - exact) < 3 * estimate.stderr


def test_hessian_diagonal_on_a_nonquadratic_tree():
    w = {"x": jnp.array([0.3, -1.2]), "y": jnp.array(0.7)}
    loss = lambda t: jnp.sum(jnp.sin(t["x"])) * t["y"] ** 2  # noqa: E731
    diagonal = theory.hessian_diagonal(loss, w, chunk_size=2)
    np.testing.assert_allclose(diagonal["x"], -jnp.sin(w["x"]) * 0.49, rtol=1e-5)
    np.testing.assert_allclose(diagonal["y"], 2 * jnp.sum(jnp.sin(w["x"])), rtol=1e-5)


@pytest.mark.parametrize("name, sign", [("convex", 1), ("concave", -1)])
def test_toy_gap_sign_for_every_sigma(name, sign):
    loss = theory.toy_loss(name)
    sigmas = jnp.array([0.01, 0.1, 0.5, 1.0, 3.0])
    mus = jnp.array([-1.5, 0.0, 0.4, 2.0])
    for k, mu in enumerate(mus):
        gaps = jax.vmap(lambda s, kk, m=mu: theory.jensen_gap(loss, m, s, kk, 2000))(
            sigmas, jax.random.split(jax.random.key(k), len(sigmas))
        )
        assert jnp.all(sign * gaps.gap > 0), (name, float(mu), gaps.gap)


def test_nonconvex_gap_matches_closed_form():
    mu, sigma = jnp.float32(0.2), jnp.array([0.1, 0.5, 1.0])
    exact = sigma**2 * (3 * mu**2 - 1) / 2 + 3 * sigma**4 / 4
    gaps = jax.vmap(lambda s, k: theory.jensen_gap(theory.nonconvex_loss, mu, s, k, 20_000))(
        sigma, jax.random.split(jax.random.key(0), 3)
    )
    assert jnp.all(jnp.abs(gaps.gap - exact) < 3 * gaps.stderr + 1e-6)


def test_sigma_step_matches_theorem_on_a_diagonal_quadratic():
    loss, a, mu, sigma = _quadratic(0, diagonal=True)
    step = theory.gradient_step(loss, mu, sigma, jax.random.key(1), 0.1, num_samples=2000)
    np.testing.assert_allclose(step.dsigma_theorem, -0.1 * a @ sigma, rtol=1e-5)
    assert jnp.all(jnp.abs(step.dsigma - step.dsigma_theorem) < 3 * step.dsigma_stderr + 1e-6)
    np.testing.assert_allclose(step.dmu, step.dmu_theorem, rtol=1e-4, atol=1e-6)


def test_sigma_step_sees_only_the_hessian_diagonal():
    """With a non-diagonal H the expected step is -lr (diag(H) + prior) sigma, not -lr H sigma."""
    loss, _, mu, sigma = _quadratic(2)
    step = theory.gradient_step(
        loss, mu, sigma, jax.random.key(2), 0.1, num_samples=4000, prior_weight=0.5
    )
    z_second_order = jnp.abs(step.dsigma - step.dsigma_second_order) / step.dsigma_stderr
    z_theorem = jnp.abs(step.dsigma - step.dsigma_theorem) / step.dsigma_stderr
    assert jnp.all(z_second_order < 4)
    assert jnp.max(z_theorem) > 20
    np.testing.assert_allclose(step.dmu, step.dmu_theorem, rtol=1e-4, atol=1e-6)


def test_train_toy_shrinks_sigma_on_convex_and_grows_it_on_concave():
    convex = theory.train_toy(theory.convex_loss, 1.0, 0.5, jax.random.key(0), gap_samples=200)
    concave = theory.train_toy(theory.concave_loss, 0.2, 0.2, jax.random.key(0), gap_samples=200)
    assert convex.mu.shape == convex.sigma.shape == convex.gap.shape == (101,)
    # on L = w^2/2 the expected step is sigma -> (1 - lr) sigma: 0.9^100 = 2.7e-5
    assert convex.sigma[-1] < 1e-3 * convex.sigma[0]
    assert concave.sigma[-1] > 2 * concave.sigma[0]
    assert jnp.all(convex.gap > 0) and jnp.all(concave.gap < 0)
    # on a quadratic the second-order prediction is exact
    assert jnp.all(jnp.abs(convex.gap - convex.prediction) < 4 * convex.gap_stderr + 1e-9)


def test_synapse_view_reproduces_the_model():
    config = ClassifierConfig(hidden=(6,), cell_types=(3, 2, 4))
    model = make_model(config, num_classes=4)
    x = jax.random.normal(jax.random.key(0), (5, 7))
    params = model.init({"params": jax.random.key(1), "sample": jax.random.key(2)}, x)
    params = {"params": jax.tree_util.tree_map(lambda p: p + 0.3, params["params"])}
    view = theory.synapse_view(model, params, x)
    assert view.mean["SGBDense_0"].shape == view.sigma["SGBDense_0"].shape == (7, 6)
    np.testing.assert_allclose(
        view.forward(view.mean, x), model.apply(params, x, mean_network=True), rtol=1e-5
    )
    key = jax.random.key(3)
    kernels = {
        name: layer["genome"]["kernel"]
        for name, layer in individual_kernels(model, params, x, key).items()
    }
    np.testing.assert_allclose(
        view.forward(kernels, x), model.apply(params, x, rngs={"sample": key}), rtol=1e-5
    )
    loss = theory.network_loss(view, x, jnp.arange(5) % 4, "error_rate")
    assert 0.0 <= float(loss(view.mean)) <= 1.0


@pytest.mark.parametrize(
    "call",
    [
        lambda: theory.toy_loss("flat"),
        lambda: theory.jensen_gap(theory.convex_loss, 0.0, 1.0, jax.random.key(0), 0),
        lambda: theory.jensen_gap(theory.convex_loss, jnp.zeros(2), jnp.ones(3), jax.random.key(0)),
        lambda: theory.second_order_trace(theory.convex_loss, 0.0, 1.0, num_probes=5),
        lambda: theory.gradient_step(theory.convex_loss, 0.0, 1.0, jax.random.key(0), -0.1),
        lambda: theory.train_toy(theory.convex_loss, 0.0, 1.0, jax.random.key(0), steps=0),
    ],
)
def test_bad_arguments_raise(call):
    with pytest.raises(ValueError):
        call()


def test_experiment_writes_results(tmp_path, monkeypatch):
    tiny = experiment.TheoryConfig(
        steps=5,
        gap_samples=40,
        map_mu0=(-1.0, 1.0, 3),
        map_sigma0=(0.1, 0.5, 2),
        breakdown_sigma=(0.1, 1.0, 3),
        classifiers=(ClassifierConfig(hidden=(8,), cell_types=(4, 4, 10), epochs=1),),
        network_individuals=8,
        sigma_scales=(1.0,),
        hutchinson_probes=4,
    )
    monkeypatch.setitem(experiment.PROFILES, "smoke", tiny)
    path = experiment.run("smoke", tmp_path)
    payload = read_results(path)
    assert payload["provenance"]["profile"] == "smoke"
    results = payload["results"]
    assert set(results["trajectories"]) == {"convex", "concave", "nonconvex"}
    assert len(results["trajectories"]["convex"]["gap"]) == 6
    assert np.asarray(results["sign_map"]["gap_end"]).shape == (3, 2)
    network = results["network"][0]
    assert network["synapses"] == 64 * 8 + 8 * 10
    assert set(network["scales"][0]) >= {"predicted", "train_cross_entropy", "test_error_rate"}
    with pytest.raises(ValueError):
        experiment.run("smoke", tmp_path, dataset="digits")
