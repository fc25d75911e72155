"""``sgb.experiments.theory``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import pytest

from sgb import claims, verdicts
from sgb.experiments import theory as theory_runs


def test_the_sigma_law_row_tells_the_appendix_step_from_the_elbo_step():
    def toy(settled):
        return {
            "kl_weights": [0.0, 0.05],
            "predicted_sigma": [0.0, 0.218],
            "steps": [0, 3000],
            "runs": {"softplus": {"settled_mean": [0.01, settled], "settled_sd": [0.01, 0.002]}},
        }

    (at_fixed_point,) = theory_runs.sigma_law_rows(theory_runs.ElboToy.model_validate(toy(0.2187)))
    assert at_fixed_point.verdict == verdicts.CONTRADICTED  # sigma stays at sqrt(c/(H+c lambda))
    (at_zero,) = theory_runs.sigma_law_rows(theory_runs.ElboToy.model_validate(toy(0.001)))
    assert at_zero.verdict == verdicts.REPRODUCED  # what the appendix's step predicts


def _trajectory(gap: float, prediction: float) -> dict:
    return {
        "mu0": 0.15,
        "sigma0": 0.25,
        "gap": [-0.03, gap],
        "gap_stderr": [0.001, 0.0005],
        "prediction": [-0.03, prediction],
    }


def _network(gap: float, predicted: float) -> dict:
    trained = {
        "scale": 1.0,
        "predicted": predicted,
        "train_cross_entropy": {"gap": gap, "stderr": 1e-4},
        "train_error_rate": {"gap": 0.0, "stderr": 0.0},
        "test_error_rate": {"gap": 0.0, "stderr": 0.0},
    }
    return {
        "cell_types": [16, 8, 10],
        "scales": [{**trained, "scale": 0.5}, trained],
        "sigma_mean": 0.01,
        "accuracy": {"mean_network": 0.9},
        "hutchinson_probes": 10,
        "hutchinson": {"value": predicted, "stderr": 1e-4},
        "layers": [{"layer": "SGBDense_0", "gap": gap, "stderr": 1e-4, "predicted": predicted}],
    }


def test_descent_rows_read_the_end_of_training_against_the_second_order_term():
    """A toy that ends below its mean network by about its second-order term reproduces
    Theorem A.2's conclusion; a network that ends above it contradicts it; the gap at half
    the trained sigma (scale 0.5) is not read."""
    theory = {
        "trajectories": {
            toy: _trajectory(-0.012, 0.0125) for toy in ("convex", "concave", "nonconvex")
        },
        "network": [_network(0.0115, 0.008)],
    }
    toy, network = theory_runs.descent_rows(theory_runs.TheoryResults.model_validate(theory))
    assert toy.setting.startswith("1-D double well from mu 0.15, sigma 0.25, after 1 steps")
    assert toy.test.estimate == -0.012 and toy.paper_effect == -0.0125
    assert toy.verdict == verdicts.REPRODUCED
    assert network.setting.startswith("digits classifier, 16/8/10 types")
    assert network.test.estimate == 0.0115 and network.paper_effect == -0.008
    assert network.verdict == verdicts.CONTRADICTED
    with pytest.raises(ValueError, match="theorem.A.2"):
        claims.judge("theorem.A.2", "s", toy.test, "b")
