"""``sgb.experiments.evolution``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

from sgb import verdicts
from sgb.experiments import (
    evolution,
)
from sgb.plots import beyond

matplotlib.use("agg")


def test_evolution_rows_find_a_known_gain_and_rule_out_a_missing_one():
    """Five seeds: at sigma 0.1 the individuals score 5 points above the deterministic
    genome of their seed, at sigma 0.2 as much as it."""
    rng = np.random.default_rng(5)
    records = []
    for seed in range(5):
        base = 0.5 + 0.02 * rng.standard_normal()  # the seed's shared start
        for sigma, gain in ((0.0, 0.0), (0.1, 5.0), (0.2, 0.0)):
            accuracy = base + gain / 100 + 0.002 * rng.standard_normal()
            spread = 0.01 if sigma else 0.0
            records.append(
                {
                    "hidden_types": 8,
                    "sigma": sigma,
                    "seed": seed,
                    "compression": 5.0,
                    "mean_fitness": np.linspace(0.1, 0.8, 300).tolist(),
                    "individuals": (accuracy + spread * rng.standard_normal(100)).tolist(),
                    "mean_network": accuracy,
                    "wall_time_s": 1.0,
                }
            )
    convergence = [evolution.convergence(r) for r in records]
    # 70 points over 299 generations: in points per 1,000 generations
    assert convergence[0]["slope"] == pytest.approx(70 / 299 * 1000, rel=1e-6)
    results = evolution.EvolutionResults.model_validate(
        {"dataset": "digits", "records": records, "convergence": convergence}
    )
    helps, flat = evolution.evolution_rows(results)
    assert helps.setting.endswith("sigma 0.1") and flat.setting.endswith("sigma 0.2")
    assert helps.verdict in verdicts.IN_DIRECTION
    assert helps.test.estimate == pytest.approx(5.0, abs=0.5)
    assert flat.verdict == verdicts.CONTRADICTED and flat.test.high < 1.0


def test_the_course_text_and_figure_follow_the_individuals_differences_along_the_way():
    """Five runs whose individuals differ at the first scoring (SD 2 points, p 0.001) and
    not at the last (SD 0.1, p 0.4); runs scored at their end only have no course."""

    def scoring(generation: int, between: float, p: float) -> dict:
        split = {"between_sd": between, "within_sd": 0.02, "icc": 0.1, "p": p}
        return {
            "generation": generation,
            "accuracy": 0.8,
            "mean_network": 0.8,
            "variance_split": split,
        }

    course = [scoring(1000, 0.02, 0.001), scoring(2000, 0.001, 0.4)]
    records = [
        evolution.EvolutionRecord.model_validate(
            {
                "hidden_types": 8,
                "sigma": 0.5,
                "seed": seed,
                "compression": 5.0,
                "mean_fitness": [0.5, 0.8],
                "individuals": [0.8, 0.81],
                "mean_network": 0.8,
                "course": course,
                "wall_time_s": 1.0,
            }
        )
        for seed in range(5)
    ]
    assert evolution._course_text(records) == (
        "its individuals differ measurably (F-test, p < 0.05) in 5 of 5 runs after 1,000 "
        "generations and in 0 after 2,000; the median SD between them 2.0 points, then 0.1"
    )
    unscored = [r.model_copy(update={"course": None}) for r in records]
    assert evolution._course_text(unscored).endswith("(these runs were scored at their end only)")
    results = SimpleNamespace(records=records)
    ax = beyond.plot_variance_course(results)
    (line,) = ax.get_lines()
    assert line.get_xdata().tolist() == [1000, 2000]
    assert line.get_ydata() == pytest.approx([2.0, 0.1])
