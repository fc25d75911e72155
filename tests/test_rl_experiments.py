"""Figure 3-5 experiment logic: sweep summaries, correlations, paired tests, profiles."""

import numpy as np
import pytest

from sgb.experiments import get_experiment, rl


def test_summary_divides_by_the_mean_vanilla_return():
    runs = [
        {"cell_types": None, "seed": 0, "final_return": 100.0},
        {"cell_types": None, "seed": 1, "final_return": 300.0},
        {"cell_types": 16, "seed": 0, "final_return": 50.0},
        {"cell_types": 16, "seed": 1, "final_return": 150.0},
    ]
    rows = {r["cell_types"]: r for r in rl.summarize_sweep(runs)}
    assert rows[None]["fraction"] == pytest.approx(1.0)
    assert rows[16]["fraction"] == pytest.approx(0.5)
    assert rows[16]["sem_fraction"] == pytest.approx(50.0 / 200.0)  # sem of (50, 150) is 50


def test_correlation_and_paired_test_on_known_populations():
    rng = np.random.default_rng(0)
    skill = rng.normal(size=60)
    returns = {
        "normal": {"individuals": skill[:, None] + 0.1 * rng.normal(size=(60, 3))},
        "long_legs": {"individuals": skill[:, None] + 0.1 * rng.normal(size=(60, 3))},
        "slippery": {"individuals": rng.normal(size=(60, 3))},
        "low_gravity": {"individuals": rng.normal(size=(60, 3))},
    }
    returns["normal"]["mean_network"] = returns["normal"]["individuals"] - 1.0
    assert rl.compare(returns, "normal", "long_legs")["r"] > 0.9
    assert abs(rl.compare(returns, "slippery", "low_gravity")["r"]) < 0.4
    test = rl.individuals_vs_mean(returns)
    assert test["t"] > 10 and test["dof"] == 59


def test_registered_profiles():
    for name in ("fig3", "fig4", "fig5"):
        module = get_experiment(name)
        assert set(module.PROFILES) == {"smoke", "cpu", "paper"}
    paper = rl.sweep_config("ant", "paper")
    assert paper.ppo.num_envs == 2048 and paper.ppo.total_steps == 50_000_000
    assert paper.cell_types == (None, 128, 64, 48, 32, 16) and len(paper.seeds) == 5
    assert rl.population_config("cpu").n_individuals == 100


def test_bad_env_raises():
    with pytest.raises(ValueError, match="env"):
        rl.sweep_config("hopper", "cpu")
    with pytest.raises(ValueError, match="env"):
        rl.run_fig4("smoke", ".", env="halfcheetah")
