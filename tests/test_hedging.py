"""Bet-hedging scores on populations whose answers are known by hand."""

import numpy as np
import pytest

from sgb import hedging


def _population(per_condition: list[list[float]]) -> np.ndarray:
    """Returns (C, N, 1): on condition c, member i returns per_condition[c][i]."""
    return np.asarray(per_condition, dtype=float)[:, :, None]


def test_a_diversified_population_outgrows_clones_with_the_higher_arithmetic_mean():
    # clones: all thrive at home (return 200), all nearly fail away (return 2)
    clones = _population([[200.0] * 4, [2.0] * 4])
    # diversified: half do well at home, half away; each generation's mean is 60
    hedged = _population([[120.0, 120.0, 0.0, 0.0], [0.0, 0.0, 120.0, 120.0]])
    scale = 100.0
    assert hedging.generation_fitness(clones, scale).tolist() == [2.0, 0.02]
    assert hedging.generation_fitness(hedged, scale).mean() < (2.0 + 0.02) / 2
    assert hedging.geometric_mean_fitness(clones, scale) == pytest.approx(np.sqrt(2.0 * 0.02))
    assert hedging.geometric_mean_fitness(hedged, scale) == pytest.approx(0.6)
    assert hedging.geometric_mean_fitness(hedged, scale) > hedging.geometric_mean_fitness(
        clones, scale
    )
    # and at least some of them survive every generation, which the clones do not
    assert hedging.p_at_least(hedged, 100.0, 2) == 1.0
    assert hedging.p_at_least(clones, 100.0, 1) == 0.5


def test_a_generation_without_fitness_sets_the_geometric_mean_to_zero_and_returns_clip_at_zero():
    extinct = _population([[50.0, 50.0], [-10.0, 0.0]])
    assert hedging.generation_fitness(extinct, 50.0).tolist() == [1.0, 0.0]
    assert hedging.geometric_mean_fitness(extinct, 50.0) == 0.0


def test_generations_are_every_episode_of_every_condition_and_survivors_are_counted_in_each():
    rng = np.random.default_rng(0)
    returns = rng.normal(100.0, 30.0, size=(4, 50, 3))
    counts = hedging.survivors(returns, 100.0)
    assert counts.shape == (12,)
    assert counts[4] == (returns[1, :, 1] >= 100.0).sum()  # condition 1, episode 1
    k = int(np.median(counts))
    assert hedging.p_at_least(returns, 100.0, k) == np.mean(counts >= k)
    w = hedging.generation_fitness(returns, 100.0)
    assert hedging.geometric_mean_fitness(returns, 100.0) <= w.mean()  # AM-GM


def test_bad_inputs_fail_with_names():
    with pytest.raises(ValueError, match="returns"):
        hedging.survivors(np.zeros((3, 4)), 1.0)
    with pytest.raises(ValueError, match="scale"):
        hedging.generation_fitness(np.ones((1, 2, 2)), 0.0)


def test_a_retest_keeps_survivors_by_ability_and_thins_survivors_by_luck_to_p_squared():
    """Two populations of 2,000 whose members each pass a generation's episode 30 % of the
    time: by ability (the same 600 members always) or by luck (each episode anew). Both
    count about 600 survivors; retested on a second episode, the able keep all 600 and the
    lucky keep N p^2 = 180 on average (its SE over 400 generations is 0.64)."""
    rng = np.random.default_rng(1)
    n, generations, p = 2000, 400, 0.3
    able = np.where(np.arange(n) < p * n, 1.0, 0.0)[None, :, None]
    able = np.broadcast_to(able, (1, n, generations))
    lucky, lucky_again = (rng.random((2, 1, n, generations)) < p).astype(float)
    assert np.all(hedging.survivors(able, 1.0, retest=able) == p * n)
    assert abs(hedging.survivors(lucky, 1.0).mean() - p * n) < 5
    assert abs(hedging.survivors(lucky, 1.0, retest=lucky_again).mean() - n * p**2) < 5
    assert hedging.p_at_least(lucky, 1.0, 250, retest=lucky_again) == 0.0
    with pytest.raises(ValueError, match="retest must have the shape"):
        hedging.survivors(lucky, 1.0, retest=lucky[:, :10])
