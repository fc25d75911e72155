"""Bet-hedging in a world that changes between generations: how a population fares when
each generation meets one of several conditions.

A population's returns are an array (C, N, E): on each of C conditions, each of N members
plays E episodes. Generation (c, e) is every member's episode e on condition c, so the
C x E generations visit every condition equally often, as a world that changes at random
among them would. Two scores of a population:

- its *geometric-mean fitness*: a member's fitness in a generation is its return clipped
  at 0 over ``scale`` (a return; the mean network's on the normal body, so 1 is that
  network at home); the population's is its members' mean, and over generations the
  geometric mean exp(mean log W) (0 if some generation has W = 0). A lineage's long-run
  growth follows this mean, not the arithmetic one, so a population whose fitness varies
  less from generation to generation can grow faster at a lower average;
- its *survival*: a member survives a generation if its return reaches ``threshold``; the
  probability that at least k of the N survive is the share of generations in which they do.
  A survivor *retested* must also reach it on a second episode from a new initial state
  (``retest``, the same shape): one survival can be an episode's luck, two in a row on
  independent states measure the member's ability.
"""

import numpy as np

from sgb import validation


def _returns(returns) -> np.ndarray:
    """``returns`` (C, N, E) as float64; every score refuses an empty or non-finite one, so
    that none of them is NaN or counts a NaN as a failure."""
    array = validation.finite_array("returns", returns, ndim=3)
    return np.asarray(array, dtype=np.float64)


def generation_fitness(returns, scale: float) -> np.ndarray:
    """The population's fitness in each generation, shape (C * E,): the members' mean of
    max(return, 0) / ``scale``, generations ordered condition by condition."""
    r = _returns(returns)
    validation.positive("scale", scale)
    per_generation = np.maximum(r, 0.0).mean(axis=1) / scale  # (C, E)
    return per_generation.reshape(-1)


def geometric_mean_fitness(returns, scale: float) -> float:
    """exp(mean log W) over the generations of ``generation_fitness``; 0 if some W is 0."""
    w = generation_fitness(returns, scale)
    if np.any(w == 0):
        return 0.0
    return float(np.exp(np.log(w).mean()))


def survivors(returns, threshold: float, retest=None) -> np.ndarray:
    """How many members reach ``threshold`` in each generation, shape (C * E,); with
    ``retest`` (C, N, E), those who reach it in both ``returns`` and ``retest``."""
    r = _returns(returns)
    passed = r >= validation.real("threshold", threshold)
    if retest is not None:
        again = _returns(retest)
        if again.shape != r.shape:
            raise ValueError(f"retest must have the shape of returns {r.shape}, got {again.shape}")
        passed &= again >= threshold
    return passed.sum(axis=1).reshape(-1)


def p_at_least(returns, threshold: float, k: int, retest=None) -> float:
    """The share of generations in which at least ``k`` members reach ``threshold`` (with
    ``retest``, in both episodes: ``survivors``)."""
    validation.integer("k", k)
    return float((survivors(returns, threshold, retest) >= k).mean())
