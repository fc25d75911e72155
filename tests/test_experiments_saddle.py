"""``sgb.experiments.saddle``: the split of Theorem A.1's term by the sign of the curvature
against closed forms, on a quadratic and on a trained classifier, and its rows on inputs
with known shares."""

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest

from sgb import theory, verdicts
from sgb.data import digits
from sgb.experiments import saddle
from sgb.supervised import train_and_evaluate


def test_the_split_of_a_quadratics_term_matches_its_eigen_decomposition():
    """On L(w) = w'Aw / 2 with A of known eigenvalues (2 of them negative) and independent
    noise of spreads sigma: P - N is the exact Jensen gap tr(A diag sigma^2) / 2, and N is
    minus half the negative eigenvalues times sigma's variance along their eigenvectors."""
    rng = np.random.default_rng(0)
    q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    lam = np.array([-2.0, -0.5, 0.1, 1.0, 3.0, 4.0])
    a = q @ np.diag(lam) @ q.T
    sigma = rng.uniform(0.1, 1.0, 6)
    eigen = theory.second_order_eigen(
        lambda w: 0.5 * w @ jnp.asarray(a) @ w, jnp.zeros(6), jnp.asarray(sigma)
    )
    positive, negative = saddle.curvature_split(eigen.eigenvalues, eigen.rho2)
    assert positive - negative == pytest.approx(0.5 * np.sum(np.diag(a) * sigma**2), rel=1e-5)
    along = (q**2 * sigma[:, None] ** 2).sum(axis=0)  # sigma's variance along each eigenvector
    assert negative == pytest.approx(-0.5 * np.sum(lam[:2] * along[:2]), rel=1e-5)


def test_a_trained_classifiers_split_agrees_with_its_hessian_diagonal():
    """On a digits classifier trained 2 epochs (no types): P - N from the dense Hessian's
    eigenvalues equals 1/2 sum_s H_ss sigma_s^2 from the Hessian's diagonal alone (one HVP
    per weight), the record counts its negative eigenvalues, and N's share lies in [0, 1]."""
    data = digits(0)
    classifier = dataclasses.replace(saddle.PROFILES["smoke"].classifiers[0], seed=0)
    trained = train_and_evaluate(classifier, data, progress=False)
    view = theory.synapse_view(trained["model"], trained["params"], data.x_train)
    loss = theory.network_loss(view, data.x_train, data.y_train, "cross_entropy")
    eigen = theory.second_order_eigen(loss, view.mean, view.sigma)
    positive, negative = saddle.curvature_split(eigen.eigenvalues, eigen.rho2)
    diagonal = theory.hessian_diagonal(loss, view.mean)
    traced = sum(0.5 * float(jnp.sum(view.sigma[k] ** 2 * diagonal[k])) for k in diagonal)
    assert positive - negative == pytest.approx(traced, rel=1e-3)
    record = saddle.curvature_record(classifier, 0, data)
    assert record["negative_eigenvalues"] == int(np.sum(np.array(record["eigenvalues"]) < 0))
    assert record["weights"] == len(record["eigenvalues"]) == 64 * 32 + 32 * 10
    assert 0 <= record["negative_share"] <= 1


def _results(shares: dict[str, list[float]]) -> saddle.SaddleResults:
    """Saddle results holding, per classifier ("none" or "typed"), one network per share."""
    types = {"none": [None, None, None], "typed": [16, 8, 10]}
    networks = [
        {
            "cell_types": types[kind],
            "seed": seed,
            "weights": 2368,
            "positive": 1.0 - share,
            "negative": share,
            "negative_share": share,
            "lambda_min": -0.1,
            "lambda_max": 2.0,
            "negative_eigenvalues": 300,
            "gradient_norm": 0.3,
            "eigenvalues": [],
        }
        for kind, values in shares.items()
        for seed, share in enumerate(values)
    ]
    return saddle.SaddleResults.model_validate({"networks": networks})


def test_the_rows_judge_the_negative_share_against_half():
    """Shares near 0.25 over 5 seeds: negative curvature, too little to turn the gap
    (smaller than the effect compared); near 0.5: reproduced; a classifier with one seed
    has no row; one with no negative curvature at any seed is contradicted."""
    rng = np.random.default_rng(3)
    rows = saddle.saddle_rows(
        _results({"none": list(0.25 + 0.01 * rng.normal(size=5)), "typed": [0.4]})
    )
    assert [r.verdict for r in rows] == [verdicts.SMALLER]
    assert "no types" in rows[0].setting
    (half,) = saddle.saddle_rows(_results({"typed": list(0.5 + 0.01 * rng.normal(size=5))}))
    assert half.verdict == verdicts.REPRODUCED and "16/8/10 types" in half.setting
    (flat,) = saddle.saddle_rows(_results({"typed": [0.0] * 3}))
    assert flat.verdict == verdicts.CONTRADICTED and flat.test is None
