"""Arguments that used to be taken and to fail far from the call, or to give a wrong answer,
are refused at the door with an error naming the argument."""

from dataclasses import replace

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from reach import SPEC, reach_config

from sgb import genome, hedging
from sgb.budget import BudgetConfig
from sgb.evolution import EvolutionConfig
from sgb.experiments.bet_hedging import HedgingConfig
from sgb.experiments.evolution import EvolutionSweep
from sgb.priors import GaussianPrior, ScaleMixturePrior
from sgb.rl import ppo
from sgb.rl.normalizer import init_normalizer
from sgb.rl.population import population_returns
from sgb.supervised import ClassifierConfig, make_model

TABLES = genome.LayerGenome(jnp.zeros((2, 3)), jnp.full((2, 3), -3.0))
SHAPES = {"a": (4, 6), "b": (6, 2)}
NOISE = {name: jnp.zeros(shape) for name, shape in SHAPES.items()}
KEY = jax.random.key(0)


def _calls(tables: genome.Genome) -> dict:
    return {
        "kernels": lambda: genome.kernels(tables, NOISE),
        "kl": lambda: genome.kl(tables, SHAPES, GaussianPrior(0.1), KEY),
        "mean_kernels": lambda: genome.mean_kernels(tables, SHAPES),
    }


@pytest.mark.parametrize("call", ["kernels", "kl", "mean_kernels"])
def test_a_genome_must_hold_every_layer_asked_for_as_layer_genomes(call):
    b = genome.LayerGenome(jnp.zeros((3, 2)), jnp.full((3, 2), -3.0))
    with pytest.raises(ValueError, match="genome has no layer 'b' of (noise|shapes)"):
        _calls({"a": TABLES})[call]()
    with pytest.raises(TypeError, match="genome\\['a'\\] must be a LayerGenome, got a tuple"):
        _calls({"a": tuple(TABLES), "b": b})[call]()
    _calls({"a": TABLES, "b": b})[call]()  # whole, it computes


@pytest.mark.parametrize("prior", [GaussianPrior(0.1), ScaleMixturePrior()])
def test_the_kl_needs_a_key(prior):
    with pytest.raises(TypeError, match="key must be a jax PRNG key"):
        genome.kl({"a": TABLES}, {"a": (4, 6)}, prior, None)


def test_genome_trees_are_flax_params_and_tables_keep_their_shape():
    with pytest.raises(TypeError, match="params must be a Flax tree.*got keys \\[\\]"):
        genome.of_params({})
    params = {"params": {"L": {"genome": {"mu": TABLES.mu, "rho": TABLES.rho}, "bias": 0.0}}}
    wide = genome.LayerGenome(jnp.zeros((5, 5)), jnp.zeros((5, 5)))
    with pytest.raises(
        ValueError,
        match="genome\\['L'\\].mu must have the shape of the tables it replaces, \\(2, 3\\)",
    ):
        genome.with_tables(params, {"L": wide})
    with pytest.raises(ValueError, match="genome\\['M'\\].rho must have mu's shape \\(5, 5\\)"):
        genome.with_tables(params, {"M": wide._replace(rho=jnp.zeros((2, 3)))})
    written = genome.with_tables(params, {"L": TABLES._replace(mu=TABLES.mu + 1), "M": wide})
    assert genome.of_params(written)["M"].mu.shape == (5, 5)  # a new layer takes any shape
    np.testing.assert_array_equal(genome.of_params(written)["L"].mu, 1.0)


def test_bet_hedging_scores_refuse_empty_or_non_finite_returns():
    with pytest.raises(ValueError, match="returns is empty"):
        hedging.p_at_least(np.ones((0, 12, 3)), 0.5, 1)
    returns = np.ones((4, 12, 3))
    returns[0, 0, 0] = np.nan
    for score in (
        lambda r: hedging.geometric_mean_fitness(r, 1.0),
        lambda r: hedging.p_at_least(r, 0.5, 1),
        lambda r: hedging.survivors(r, 0.5),
    ):
        with pytest.raises(ValueError, match="returns holds nan"):
            score(returns)
    assert hedging.p_at_least(np.ones((4, 12, 3)), 0.5, 12) == 1.0


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (lambda: EvolutionConfig(sigma=-0.1), ValueError, "sigma must be"),
        (lambda: EvolutionConfig(sigma=float("nan")), ValueError, "sigma must be"),
        (
            lambda: EvolutionSweep("bogus", EvolutionConfig(), (2,), (0.0,), (0,)),
            ValueError,
            "dataset must be one of",
        ),
        (
            lambda: EvolutionSweep("digits", EvolutionConfig(), (2,), (0.1, 0.0), (0,)),
            ValueError,
            "sigmas must start at 0",
        ),
        (lambda: HedgingConfig((), (0,)), ValueError, "rho_inits must not be empty"),
        (lambda: HedgingConfig((-5.0, -5), (0,)), ValueError, "rho_inits must not repeat"),
        (lambda: HedgingConfig((-5.0,), (0, 1, 0)), ValueError, "seeds must not repeat.*0 rep"),
        (lambda: HedgingConfig((-5.0,), (0,), seed=2**40), ValueError, "seed must be < 2\\*\\*32"),
        (lambda: HedgingConfig((-5.0,), (0, 1), seed=2**32 - 1), ValueError, "seed \\+ j"),
        (lambda: BudgetConfig(dataset=None), TypeError, "dataset must be a str"),
        (lambda: ClassifierConfig(local_reparam="yes"), TypeError, "local_reparam must be a bool"),
        (
            lambda: ppo.PPOConfig(total_steps=4096, num_evals=5),
            ValueError,
            "total_steps=4096 must hold at least one iteration of 2048 steps per evaluation",
        ),
    ],
)
def test_invalid_configs_are_refused_when_built(make, error, match):
    with pytest.raises(error, match=match):
        make()


def test_configs_at_the_edges_are_taken():
    assert HedgingConfig((-5.0,), (0, 1), seed=2**32 - 2).genomes() == [(-5.0, 0), (-5.0, 1)]
    config = ppo.PPOConfig(total_steps=5 * 2048, num_evals=5)
    chunk = config.iterations // config.num_evals
    assert config.num_evals * chunk * config.steps_per_iteration <= config.total_steps
    cells = EvolutionSweep("digits", EvolutionConfig(), (2,), (0.0, 1e-9), (0,)).cells()
    assert [c.sigma for c in cells] == [0.0, 1e-9] and not cells[0].stochastic


def test_a_classifier_model_is_built_for_an_input_width():
    config = ClassifierConfig(hidden=(6,), cell_types=(3, 2, None))
    with pytest.raises(TypeError, match="input_shape"):
        make_model(config, 4)  # its genome, a type table, cannot tell the width it was made for
    with pytest.raises(TypeError, match="input_shape must be a sequence of integers"):
        make_model(config, 4, None)
    model = make_model(config, 4, (6,))
    params = model.init({"params": KEY, "sample": KEY}, jnp.zeros((1, 6)))
    with pytest.raises(ValueError, match="in_features=6 inputs, got 12"):
        model.apply(params, jnp.zeros((2, 12)), mean_network=True)


def test_population_returns_refuse_the_actor_of_another_network():
    two, four = reach_config(2), reach_config(4)
    actor = ppo.initial_params(two, seed=0).actor
    with pytest.raises(ValueError, match="actor_params do not have the shapes.*network"):
        population_returns(SPEC, four.network, actor, init_normalizer(2), 2, 1, 4)
    wider = replace(two.network, hidden=(32, 33))
    with pytest.raises(ValueError, match="actor_params do not have the shapes"):
        population_returns(SPEC, wider, actor, init_normalizer(2), 2, 1, 4)
