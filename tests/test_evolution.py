"""Evolution without gradients: the strategy learns from fitness alone, a deterministic
genome develops one network, and fitness is the accuracy of the developed networks."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from sgb import genome
from sgb.data import load
from sgb.evolution import TEST_PARTS, EvolutionConfig, accuracies, develop, evolve, part_accuracies
from sgb.individuals import init_params
from sgb.layers import SGBMLP

SMALL = EvolutionConfig(hidden=16, candidates=16, individuals=4, generations=80, batch_size=128)


@pytest.fixture(scope="module")
def digits():
    return load("digits", seed=0)


def test_evolution_lifts_innate_accuracy_far_above_chance_from_fitness_alone(digits):
    result = evolve(dataclasses.replace(SMALL, sigma=0.1, eval_individuals=20), digits)
    assert result["mean_fitness"][0] < 0.2  # ten classes: chance is 0.1
    assert np.mean(result["mean_fitness"][-5:]) > 0.3
    assert np.mean(result["individuals"]) > 0.25  # on the test set
    split = result["variance_split"]
    assert split["within_sd"] > 0 and 0 <= split["p"] <= 1


def test_scoring_along_the_way_leaves_the_evolution_as_it_was(digits):
    """Cut into 4 spans, the same 40 generations give the same fitness curves; each span
    is scored, and the last score is the end's."""
    config = dataclasses.replace(SMALL, sigma=0.3, generations=40, eval_individuals=12)
    whole = evolve(config, digits)
    spans = evolve(dataclasses.replace(config, scorings=4), digits)
    np.testing.assert_allclose(spans["mean_fitness"], whole["mean_fitness"], rtol=1e-6)
    np.testing.assert_allclose(spans["best_fitness"], whole["best_fitness"], rtol=1e-6)
    assert [p["generation"] for p in spans["course"]] == [10, 20, 30, 40]
    last = spans["course"][-1]
    assert last["accuracy"] == pytest.approx(np.mean(spans["individuals"]))
    assert last["variance_split"] == spans["variance_split"]
    assert spans["individuals"] == pytest.approx(whole["individuals"], abs=1e-6)
    with pytest.raises(ValueError, match="must divide"):
        dataclasses.replace(config, scorings=3)


def test_a_deterministic_genome_develops_its_mean_network_alone(digits):
    result = evolve(dataclasses.replace(SMALL, generations=5), digits)
    assert set(result["individuals"]) == {result["mean_network"]}
    assert "variance_split" not in result


def test_accuracies_score_each_network_on_its_own_batch_and_the_mean_network_on_each():
    """Labels are the mean network's: it scores 1 on every batch; networks drawn at sigma
    0.3 miss some; at sigma 1e-9 they are the mean network. The parts of the test set
    average to the whole."""
    model = SGBMLP((8, 3), (2, 4, None), in_features=4)
    x = jax.random.normal(jax.random.key(0), (5, 60, 4))  # 5 batches of 60
    params = init_params(model, jax.random.key(1), x[0, :1])
    mu = {n: t.mu for n, t in genome.of_params(params).items()}
    mean = develop(params, mu, 0.0)
    y = jnp.argmax(model.apply(mean, x, mean_network=True), -1)
    keys = jax.random.split(jax.random.key(2), 5)
    assert accuracies(model, mean, x, y, keys, False).tolist() == [1.0] * 5
    drawn = accuracies(model, develop(params, mu, 0.3), x, y, keys, True)
    assert drawn.shape == (5,) and float(drawn.max()) < 1.0
    assert accuracies(model, develop(params, mu, 1e-9), x, y, keys, True).tolist() == [1.0] * 5
    flat_x, flat_y = x.reshape(-1, 4), y.reshape(-1)
    parts = part_accuracies(model, develop(params, mu, 0.3), flat_x, flat_y, keys, True)
    assert parts.shape == (5, TEST_PARTS)
    whole = accuracies(
        model,
        develop(params, mu, 0.3),
        jnp.broadcast_to(flat_x, (5, 300, 4)),
        jnp.broadcast_to(flat_y, (5, 300)),
        keys,
        True,
    )
    np.testing.assert_allclose(parts.mean(axis=1), whole, atol=1e-6)
