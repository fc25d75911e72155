"""``sgb.experiments.evolution``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import numpy as np
import pytest

from sgb import verdicts
from sgb.experiments import (
    evolution,
)


def test_evolution_rows_find_a_known_gain_and_rule_out_a_missing_one():
    rng = np.random.default_rng(5)
    records = []
    for seed in range(5):
        for k, gain in ((2, 5.0), (8, 0.0)):
            base = 0.5 + 0.02 * rng.standard_normal()  # the seed's shared start
            for stochastic in (True, False):
                accuracy = base + (gain / 100 if stochastic else 0) + 0.002 * rng.standard_normal()
                individuals = (accuracy + 0.01 * rng.standard_normal(100)).tolist()
                records.append(
                    {
                        "hidden_types": k,
                        "stochastic": stochastic,
                        "seed": seed,
                        "compression": 40.0 / k,
                        "mean_fitness": [0.1] * 300,
                        "individuals": individuals if stochastic else [accuracy] * 100,
                        "mean_network": accuracy,
                        "sigma_mean": 0.1 if stochastic else 0.0,
                        "wall_time_s": 1.0,
                    }
                )
    results = evolution.EvolutionResults.model_validate({"dataset": "digits", "records": records})
    helps, flat = evolution.evolution_rows(results)
    assert helps.verdict in verdicts.IN_DIRECTION
    assert helps.test.estimate == pytest.approx(5.0, abs=0.5)
    assert flat.verdict == verdicts.CONTRADICTED and flat.test.high < 1.0
