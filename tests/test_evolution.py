"""Evolution without gradients: the strategy learns from fitness alone, a deterministic
genome develops one network, and fitness is the accuracy of the developed networks."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from sgb import genome
from sgb.data import load
from sgb.evolution import EvolutionConfig, accuracies, evolve
from sgb.individuals import init_params
from sgb.layers import SGBMLP

SMALL = EvolutionConfig(hidden=16, candidates=16, individuals=4, generations=80, batch_size=128)


@pytest.fixture(scope="module")
def digits():
    return load("digits", seed=0)


def test_evolution_lifts_innate_accuracy_far_above_chance_from_fitness_alone(digits):
    result = evolve(SMALL, digits)
    assert result["mean_fitness"][0] < 0.2  # ten classes: chance is 0.1
    assert np.mean(result["mean_fitness"][-5:]) > 0.3
    assert np.mean(result["individuals"]) > 0.25  # on the test set
    assert 0.05 < result["sigma_mean"] < 0.3  # softplus(-2) = 0.127 to start


def test_a_deterministic_genome_develops_its_mean_network_alone(digits):
    result = evolve(dataclasses.replace(SMALL, stochastic=False, generations=5), digits)
    assert set(result["individuals"]) == {result["mean_network"]}
    assert result["sigma_mean"] == 0.0


def test_accuracies_score_each_developed_network_and_the_mean_network_once():
    model = SGBMLP((8, 3), (2, 4, None), rho_init=-1.0, in_features=4)
    x = jax.random.normal(jax.random.key(0), (64, 4))
    params = init_params(model, jax.random.key(1), x[:1])
    tables = genome.of_params(params)
    y = jnp.argmax(model.apply(params, x, mean_network=True), -1)  # the mean network's labels
    solution = {
        "mu": {n: t.mu for n, t in tables.items()},
        "rho": {n: t.rho for n, t in tables.items()},
    }
    keys = jax.random.split(jax.random.key(2), 5)
    assert accuracies(model, params, {"mu": solution["mu"]}, x, y, keys).tolist() == [1.0]
    individuals = accuracies(model, params, solution, x, y, keys)
    assert individuals.shape == (5,) and float(individuals.max()) < 1.0  # sigma ~ 0.31
    sharp = {"mu": solution["mu"], "rho": {n: r - 20.0 for n, r in solution["rho"].items()}}
    assert accuracies(model, params, sharp, x, y, keys).tolist() == [1.0] * 5
