"""Figures 4 and 5's evaluation protocols on a trained agent: its individuals on several
conditions (bodies, niches) beside its mean network on the same initial states, and the
authors' Figure 5 protocol (sampled actions, independent initial states).

Returns are (individuals, episodes) arrays of undiscounted episode returns.
"""

from dataclasses import dataclass, field, replace
from pathlib import Path

from sgb import stats
from sgb.profiles import check_profile
from sgb.rl import checkpoints
from sgb.rl.normalizer import Normalizer
from sgb.rl.population import population_returns
from sgb.rl.ppo import PPOConfig
from sgb.rl.runs import CHECKPOINT_DIR, checkpoint_name


@dataclass(frozen=True)
class PopulationConfig:
    """Figures 4 and 5: which checkpoint, how many individuals, episodes and steps.

    ``sampled_episodes`` and ``mean_network_episodes`` size the authors' Figure 5
    protocol: each individual plays ``sampled_episodes`` episodes with sampled actions,
    the mean network ``mean_network_episodes`` episodes.
    """

    checkpoint: str
    n_individuals: int = 100
    episodes: int = 5
    episode_length: int = 1000
    seed: int = 0
    conditions: tuple[str, ...] = field(default=("normal", "long_legs", "slippery", "low_gravity"))
    mean_network_conditions: tuple[str, ...] = ("normal",)
    sampled_episodes: int = 10
    mean_network_episodes: int = 1000


def load_agent(checkpoint: Path) -> tuple[PPOConfig, dict, Normalizer]:
    """The PPO settings, actor parameters and observation normalizer kept in ``checkpoint``."""
    ppo, params, normalizer, _ = checkpoints.load(checkpoint)
    return ppo, params.actor, normalizer


def population_on(
    ppo: PPOConfig, actor_params: dict, normalizer: Normalizer, config: PopulationConfig
) -> dict:
    """``evaluate_conditions`` for an agent in memory: ``ppo`` gives its env and network."""
    out = {}
    for variant in config.conditions:
        spec = replace(ppo.env, variant=variant)
        common = (
            spec,
            ppo.network,
            actor_params,
            normalizer,
            config.n_individuals,
            config.episodes,
            config.episode_length,
            config.seed,
        )
        out[variant] = {"individuals": population_returns(*common)}
        if variant in config.mean_network_conditions:
            out[variant]["mean_network"] = population_returns(*common, mean_network=True)
    return out


def compare(returns: dict, a: str, b: str) -> dict:
    """Pearson r (with p) of the individuals' mean returns on conditions ``a`` and ``b``."""
    x = returns[a]["individuals"].mean(axis=1)
    y = returns[b]["individuals"].mean(axis=1)
    r = stats.fisher_r(x, y)
    return {"conditions": [a, b], "r": r.estimate, "p": r.p, "n": len(x)}


def individuals_vs_mean(returns: dict, condition: str = "normal") -> dict:
    """Paired t-test of each individual's mean return against the mean network's on the
    same initial states, and 99% confidence intervals of both."""
    ind = returns[condition]["individuals"].mean(axis=1)
    mean_net = returns[condition]["mean_network"].mean(axis=1)
    t = stats.paired(ind, mean_net)
    return {
        "condition": condition,
        "t": t.statistic,
        "p": t.p,
        "dof": t.dof,
        "individuals_ci99": stats.mean_ci(ind, 0.99),
        "mean_network_ci99": stats.mean_ci(mean_net, 0.99),
    }


def authors_protocol(
    ppo: PPOConfig, actor_params: dict, normalizer: Normalizer, config: PopulationConfig
) -> dict:
    """Figure 5 as the authors' code runs it: each individual plays ``sampled_episodes``
    episodes and the mean network ``mean_network_episodes``, all with sampled actions and
    independent initial states; one-sample t-test of the individuals' mean returns
    against the mean network's mean return, taken as a fixed value."""
    common = (ppo.env, ppo.network, actor_params, normalizer)
    individuals = population_returns(
        *common,
        config.n_individuals,
        config.sampled_episodes,
        config.episode_length,
        seed=config.seed + 1,
        stochastic=True,
    )
    mean_network = population_returns(
        *common,
        config.mean_network_episodes,
        1,
        config.episode_length,
        seed=config.seed + 2,
        mean_network=True,
        stochastic=True,
    )[:, 0]
    t = stats.one_sample(individuals.mean(axis=1), float(mean_network.mean()))
    return {
        "individuals": individuals,
        "mean_network": mean_network,
        "t": t.statistic,
        "p": t.p,
        "dof": t.dof,
        "individuals_ci99": stats.mean_ci(individuals.mean(axis=1), 0.99),
        "mean_network_ci99": stats.mean_ci(mean_network, 0.99),
    }


def population_config(profile: str) -> PopulationConfig:
    """Figures 4 and 5 settings: the committed cpu checkpoint of the Ant with 64 cell types."""
    check_profile(profile)
    source = "paper" if profile == "paper" else "cpu"
    checkpoint = str(CHECKPOINT_DIR / checkpoint_name("ant", 64, 0, source))
    if profile == "smoke":
        return PopulationConfig(
            checkpoint,
            n_individuals=8,
            episodes=2,
            episode_length=100,
            sampled_episodes=2,
            mean_network_episodes=16,
        )
    return PopulationConfig(checkpoint, episodes=3)
