import dataclasses

import jax
import numpy as np
import pytest

from sgb.data import digits
from sgb.experiments.bayes_by_backprop import PROFILES, classifier_variants, fit_regression
from sgb.supervised import train_and_evaluate


@pytest.mark.parametrize("variant", ["SGB, KL per synapse", "SGB, KL per type pair, local"])
def test_smoke_sgb_classifier_on_digits_beats_80_percent(variant):
    config = classifier_variants(PROFILES["smoke"])[variant]
    assert config.cell_types[1] < config.hidden[0]  # the hidden layer really is compressed
    result = train_and_evaluate(config, digits(seed=0), progress=False)
    accuracy = result["accuracy"]
    assert accuracy["population_average"] > 0.80
    assert len(accuracy["individuals"]) == config.eval_individuals
    assert len(set(accuracy["individuals"])) > 1  # sampled individuals differ


def test_bayesian_regression_fits_the_data_and_is_unsure_away_from_it():
    config = dataclasses.replace(PROFILES["smoke"], regression_epochs=800)
    fit = fit_regression(config, progress=False)
    grid, mean, std = fit["grid"], fit["mean"], fit["std"]
    on_data = (np.abs(grid) > 0.45) & (np.abs(grid) < 0.9)
    rmse = np.sqrt(np.mean((mean[on_data] - np.sin(3 * grid[on_data])) ** 2))
    assert rmse < 0.2
    outside = np.abs(grid) > 1.4
    assert std[outside].mean() > 2 * std[on_data].mean()


def test_training_is_reproducible_from_its_seed():
    config = dataclasses.replace(
        classifier_variants(PROFILES["smoke"])["SGB, KL per synapse"], epochs=1, hidden=(16,)
    )
    data = digits(seed=0)
    a = train_and_evaluate(config, data, progress=False)
    b = train_and_evaluate(config, data, progress=False)
    for x, y in zip(
        jax.tree_util.tree_leaves(a["params"]), jax.tree_util.tree_leaves(b["params"]), strict=True
    ):
        np.testing.assert_array_equal(x, y)
    assert a["accuracy"] == b["accuracy"]


def test_bad_training_arguments_raise():
    config = classifier_variants(PROFILES["smoke"])["BNN (k = n)"]
    with pytest.raises(ValueError, match="epochs"):
        dataclasses.replace(config, epochs=0)
