"""Tests of sgb.theory: the Jensen gap, its second-order predictions, the (mu, sigma) step."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from sgb import genome, theory
from sgb.experiments import theory as experiment
from sgb.individuals import individual_kernels
from sgb.priors import GaussianPrior, ScaleMixturePrior
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


# --- the sigma step of the ELBO ---------------------------------------------------------------


def _exact_quadratic_elbo(curvature, kl_weight, prior_sigma, parameterisation):
    """The Monte-Carlo-free ELBO of L(w) = h w^2 / 2, whose E[L] is h (mu^2 + sigma^2) / 2."""
    to_sigma = (lambda r: r) if parameterisation == "sigma" else jax.nn.softplus

    def objective(params):
        m, raw = params
        s = to_sigma(raw)
        return 0.5 * curvature * (m**2 + s**2) + kl_weight * theory.gaussian_kl(m, s, prior_sigma)

    return objective, to_sigma


def test_gaussian_kl_is_the_layers_closed_form():
    mu = jnp.array([0.0, 0.3, -1.2])
    sigma = jnp.array([0.05, 0.3, 2.0])
    np.testing.assert_allclose(
        theory.gaussian_kl(mu, sigma, 0.4), jnp.sum(GaussianPrior(0.4).kl(mu, sigma)), rtol=1e-6
    )
    grad = jax.grad(lambda s: theory.gaussian_kl(jnp.float32(0.0), s, 1.0))
    assert jnp.isfinite(grad(jnp.float32(1e-30))) and grad(jnp.float32(0.0)) == 0


def test_elbo_sigma_step_has_three_terms():
    sigma, curvature, c, sp, lr = jnp.array([0.2, 0.5]), jnp.array([3.0, -1.0]), 0.1, 0.5, 0.05
    step = theory.elbo_sigma_step(sigma, curvature, c, sp, lr)
    np.testing.assert_allclose(step.data, -lr * curvature * sigma, rtol=1e-6)
    np.testing.assert_allclose(step.prior, -lr * c * sigma / sp**2, rtol=1e-6)
    np.testing.assert_allclose(step.entropy, lr * c / sigma, rtol=1e-6)
    expected = -lr * ((curvature + c / sp**2) * sigma - c / sigma)
    np.testing.assert_allclose(step.total, expected, rtol=1e-5)
    # it is minus lr times the gradient of the exact quadratic ELBO
    for s, h in zip(sigma, curvature, strict=True):
        objective, _ = _exact_quadratic_elbo(h, c, sp, "sigma")
        grad = jax.grad(objective)((jnp.float32(0.3), s))[1]
        np.testing.assert_allclose(theory.elbo_sigma_step(s, h, c, sp, lr).total, -lr * grad, 1e-5)
    # softplus: the chain-rule factor sigmoid(rho) = 1 - exp(-sigma) on every term
    soft = theory.elbo_sigma_step(sigma, curvature, c, sp, lr, parameterisation="softplus")
    factor = jax.nn.sigmoid(theory.softplus_inverse(sigma))
    np.testing.assert_allclose(soft.total, factor * step.total, rtol=1e-5)
    np.testing.assert_allclose(jax.nn.softplus(theory.softplus_inverse(sigma)), sigma, rtol=1e-6)


def test_without_the_kl_the_step_is_the_appendix_step():
    """c -> 0 gives the paper's -lr H sigma; dropping only the entropy gives its eq. (14) step."""
    loss, a, mu, sigma = _quadratic(0, diagonal=True)
    lr, sp = 0.1, 0.5
    paper = theory.gradient_step(loss, mu, sigma, jax.random.key(0), lr, num_samples=8)
    for c in (1e-4, 1e-6, 0.0):
        step = theory.elbo_sigma_step(sigma, jnp.diag(a), c, sp, lr)
        np.testing.assert_allclose(step.total, paper.dsigma_theorem, atol=2 * c / 0.2, rtol=1e-5)
    c = 0.3
    decay = theory.gradient_step(
        loss, mu, sigma, jax.random.key(0), lr, num_samples=8, prior_weight=c / sp**2
    )
    step = theory.elbo_sigma_step(sigma, jnp.diag(a), c, sp, lr)
    np.testing.assert_allclose(step.data + step.prior, decay.dsigma_second_order, rtol=1e-5)
    assert jnp.all(step.entropy > 0)


def test_fixed_point_is_the_zero_of_the_step():
    c, sp = 0.2, 0.5  # c lambda = 0.8
    curvature = jnp.array([5.0, 0.5, 0.0, -0.5, -0.8, -2.0])
    sigma2 = theory.elbo_fixed_point(curvature, c, sp)
    np.testing.assert_allclose(sigma2[:4], c / (curvature[:4] + c / sp**2), rtol=1e-6)
    assert jnp.all(jnp.isinf(sigma2[4:]))  # H <= -c lambda: no fixed point
    assert sigma2[0] < sigma2[1] < sigma2[3] and sigma2[2] == pytest.approx(sp**2)
    assert sigma2[1] < sp**2 < sigma2[3]  # negative curvature: above the prior's scale
    for parameterisation in theory.PARAMETERISATIONS:
        step = theory.elbo_sigma_step(
            jnp.sqrt(sigma2[:4]), curvature[:4], c, sp, parameterisation=parameterisation
        )
        np.testing.assert_allclose(step.total, 0.0, atol=1e-6)
    # no KL: sigma collapses where H > 0 and has no fixed point where H <= 0
    np.testing.assert_array_equal(theory.elbo_fixed_point(curvature, 0.0, sp) == 0, curvature > 0)


@pytest.mark.parametrize("parameterisation", ["sigma", "softplus"])
@pytest.mark.parametrize("curvature", [2.0, 0.5, -0.3])
def test_exact_elbo_descent_settles_at_the_fixed_point(curvature, parameterisation):
    c, sp = 0.5, 1.0  # c lambda = 0.5 > 0.3: a fixed point even at negative curvature
    objective, to_sigma = _exact_quadratic_elbo(curvature, c, sp, parameterisation)
    grad = jax.grad(objective)
    sigma0 = jnp.float32(0.05)
    raw0 = sigma0 if parameterisation == "sigma" else theory.softplus_inverse(sigma0)

    def step(params, _):
        return tuple(p - 0.05 * g for p, g in zip(params, grad(params), strict=True)), None

    (mu, raw), _ = jax.lax.scan(step, (jnp.float32(1.0), raw0), None, length=20_000)
    expected = jnp.sqrt(theory.elbo_fixed_point(curvature, c, sp))
    np.testing.assert_allclose(to_sigma(raw), expected, rtol=1e-4)
    assert abs(mu) < 1e-5


def test_sampled_elbo_gradient_matches_the_expected_step():
    loss, _, mu, sigma = _quadratic(2)  # coupled, indefinite
    step = theory.elbo_gradient_step(
        loss, mu, sigma, jax.random.key(3), 0.1, kl_weight=0.3, prior_sigma=0.7, num_samples=4000
    )
    z = jnp.abs(step.dsigma - step.predicted.total) / step.dsigma_stderr
    assert jnp.all(z < 4)
    assert jnp.max(jnp.abs(step.dsigma - step.paper) / step.dsigma_stderr) > 20
    np.testing.assert_allclose(step.dmu, step.dmu_predicted, rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("parameterisation", ["sigma", "softplus"])
def test_sampled_elbo_descent_settles_at_the_fixed_point(parameterisation):
    c = 0.05
    run = theory.train_elbo_toy(
        theory.convex_loss,
        1.5,
        0.6,
        jax.random.key(0),
        c,
        prior_sigma=1.0,
        steps=3000,
        learning_rate=0.1,
        num_samples=256,
        parameterisation=parameterisation,
    )
    assert run.sigma.shape == run.mu.shape == (3001,)
    expected = jnp.sqrt(theory.elbo_fixed_point(1.0, c, 1.0))
    np.testing.assert_allclose(run.sigma[-1000:].mean(), expected, rtol=0.01)
    # with no KL the same descent collapses sigma (the appendix's picture)
    collapse = theory.train_elbo_toy(
        theory.convex_loss, 1.5, 0.6, jax.random.key(0), 0.0, steps=3000, learning_rate=0.1
    )
    assert collapse.sigma[-1] < 1e-6 and jnp.all(jnp.isfinite(collapse.sigma))


def test_population_hessian_diagonal_averages_over_individuals():
    mu, sigma = jnp.array([0.5, -1.0, 0.0]), jnp.array([0.3, 0.1, 0.8])
    quartic = lambda w: jnp.sum(w**4) / 4  # noqa: E731  (H_ss = 3 w_s^2)
    average = theory.population_hessian_diagonal(quartic, mu, sigma, jax.random.key(0), 4000)
    expected = 3 * (mu**2 + sigma**2)
    stderr = 3 * jnp.sqrt(4 * mu**2 * sigma**2 + 2 * sigma**4) / jnp.sqrt(4000)
    assert jnp.all(jnp.abs(average - expected) < 4 * stderr)


@pytest.mark.parametrize("counting", ["synapse", "table"])
def test_genome_fixed_point_per_type_pair(counting):
    config = ClassifierConfig(hidden=(6,), cell_types=(3, 2, 4))
    model = make_model(config, num_classes=4, input_shape=(6,)).clone(kl_counting=counting)
    x = jax.random.normal(jax.random.key(0), (5, 6))
    params = model.init({"params": jax.random.key(1), "sample": jax.random.key(2)}, x)
    diag = {
        name: jax.random.uniform(jax.random.key(i), kernel.shape)
        for i, (name, kernel) in enumerate(theory.synapse_view(model, params, x).mean.items())
    }
    c = 0.01
    fixed = theory.genome_fixed_point(model, params, diag, c)
    layer = fixed["SGBDense_0"]  # 6 x 6 synapses, 3 x 2 types: blocks of 2 x 3
    assert layer.sigma2.shape == layer.curvature.shape == layer.predicted.shape == (3, 2)
    np.testing.assert_array_equal(layer.count, 6)
    block = diag["SGBDense_0"][:2, :3]
    expected = block.mean() if counting == "synapse" else block.sum()
    np.testing.assert_allclose(layer.curvature[0, 0], expected, rtol=1e-5)
    np.testing.assert_allclose(layer.predicted, c / (layer.curvature + c / 0.1**2), rtol=1e-5)
    rho = genome.of_params(params)["SGBDense_0"].rho
    np.testing.assert_allclose(layer.sigma2, jax.nn.softplus(rho) ** 2, rtol=1e-6)
    with pytest.raises(ValueError):
        theory.genome_fixed_point(model.clone(prior=ScaleMixturePrior()), params, diag, c)


def test_relu_network_hessian_diagonal_is_not_negative():
    """One weight enters a ReLU network's logits piecewise linearly, so only the Gauss-Newton
    part of d^2 L / d w_s^2 remains: the diagonal is >= 0 (away from the kinks)."""
    config = ClassifierConfig(hidden=(8,), cell_types=(None, None, None))
    model = make_model(config, num_classes=3, input_shape=(5,))
    x = jax.random.normal(jax.random.key(0), (20, 5))
    params = model.init({"params": jax.random.key(1), "sample": jax.random.key(2)}, x)
    params = {"params": jax.tree_util.tree_map(lambda p: 3 * p + 0.1, params["params"])}
    view = theory.synapse_view(model, params, x)
    loss = theory.network_loss(view, x, jnp.arange(20) % 3, "cross_entropy")
    diagonal = theory.hessian_diagonal(loss, view.mean)
    assert all(float(d.min()) >= -1e-7 for d in diagonal.values())
    assert all(float(d.max()) > 0 for d in diagonal.values())


def test_fixed_point_summary():
    predicted = np.array([1.0, 2.0, 4.0, np.inf])
    summary = experiment.fixed_point_summary(np.array([1.0, 2.0, 8.0, 5.0]), predicted)
    assert summary["pairs"] == 3
    assert summary["median_ratio"] == 1.0
    assert summary["within_2x"] == 1.0
    assert 0.9 < summary["log_correlation"] <= 1.0


def test_synapse_view_reproduces_the_model():
    config = ClassifierConfig(hidden=(6,), cell_types=(3, 2, 4))
    model = make_model(config, num_classes=4, input_shape=(7,))
    x = jax.random.normal(jax.random.key(0), (5, 7))
    params = model.init({"params": jax.random.key(1), "sample": jax.random.key(2)}, x)
    params = {"params": jax.tree_util.tree_map(lambda p: p + 0.3, params["params"])}
    view = theory.synapse_view(model, params, x)
    assert view.mean["SGBDense_0"].shape == view.sigma["SGBDense_0"].shape == (7, 6)
    np.testing.assert_allclose(
        view.forward(view.mean, x), model.apply(params, x, mean_network=True), rtol=1e-5
    )
    key = jax.random.key(3)
    kernels = individual_kernels(model, params, x, key)
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
        lambda: theory.elbo_sigma_step(0.1, 1.0, 0.1, prior_sigma=0.0),
        lambda: theory.elbo_sigma_step(0.1, 1.0, -0.1, 1.0),
        lambda: theory.elbo_sigma_step(0.1, 1.0, 0.1, 1.0, parameterisation="log"),
        lambda: theory.elbo_fixed_point(1.0, -1.0, 1.0),
        lambda: theory.train_elbo_toy(theory.convex_loss, 0.0, -1.0, jax.random.key(0), 0.1),
        lambda: theory.population_hessian_diagonal(theory.convex_loss, 0.0, 1.0, None, 0),
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
        elbo_kl_weights=(0.0, 0.1),
        elbo_steps=20,
        elbo_record_every=5,
        settle_epochs=(2,),
        population_hessians=1,
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
    assert "fixed_point" not in network
    (fixed,) = results["fixed_point"]
    assert [run["epochs"] for run in fixed["runs"]] == [1, 2]
    layers = fixed["runs"][0]["layers"]
    assert len(layers["SGBDense_0"]["sigma2"]) == 4 * 4 and len(layers["SGBDense_1"]["count"]) == 40
    assert fixed["runs"][1]["kl_weight"] == pytest.approx(1 / 1347)
    assert set(fixed["runs"][0]["summary"]) == {"at_mean", "population"}
    toy = results["elbo_toy"]
    assert np.asarray(toy["runs"]["softplus"]["sigma"]).shape == (2, 5)
    assert len(toy["steps"]) == 5 and toy["predicted_sigma"][0] == 0
    rows = experiment.fixed_point_rows(experiment.TheoryResults.model_validate(results).fixed_point)
    assert [row["epochs"] for row in rows] == [1, 2] and rows[0]["cell types"] == "4/4/10"
    with pytest.raises(ValueError):
        experiment.run("smoke", tmp_path, dataset="digits")
