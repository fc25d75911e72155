"""Beyond Figure 5 (registered as ``spread``): does a wider genome beat its mean network?

At our default initial spread (rho = -5, sigma = 0.0067; the authors' code starts at -7,
sigma = 0.0009) the trained Ant's individuals play almost exactly like the mean network
(chapter 5). Here SGB agents (64 cell types)
are trained from several initial spreads ``rho_init``, with the Figure 3 PPO settings,
and each trained genome's individuals are compared with its mean network on the same
initial states, as in Figure 5.
"""

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from sgb import genome
from sgb.profiles import check_profile
from sgb.prose import Card
from sgb.recording import start
from sgb.results import Records
from sgb.rl.ppo import PPOConfig
from sgb.rl.protocols import (
    PopulationConfig,
    individuals_vs_mean,
    load_agent,
    population_config,
    population_on,
)
from sgb.rl.runs import CHECKPOINT_DIR, checkpoint_name, seed_sem, trained_run
from sgb.rl.sweep import ant_genome_ppo
from sgb.schemas import (
    Count,
    Finite,
    List,
    NonNegative,
    Positive,
    Probability,
    Record,
    ResultsFile,
    Return,
    Seed,
)


@dataclass(frozen=True)
class SpreadConfig:
    """Initial spreads (rho, sigma = softplus(rho)), seeds, PPO and population settings."""

    rho_inits: tuple[float, ...]
    seeds: tuple[int, ...]
    ppo: PPOConfig
    population: PopulationConfig


def spread_config(profile: str) -> SpreadConfig:
    """The spread sweep at ``profile``: Figure 3's Ant PPO with 64 cell types."""
    check_profile(profile)
    ppo = ant_genome_ppo(profile)
    population = replace(population_config(profile), conditions=("normal",))
    if profile == "smoke":
        return SpreadConfig((-5.0, -2.0), (0,), ppo, population)
    seeds = (0, 1, 2) if profile == "cpu" else (0, 1, 2, 3, 4)
    return SpreadConfig((-5.0, -3.0, -1.5), seeds, ppo, population)


def summarise_spread(runs: list[dict]) -> list[dict]:
    """Per initial spread: the population's advantage over its mean network (individuals'
    mean return minus the mean network's, mean and SEM over seeds), the spread of the
    individuals' returns and the trained sigma."""
    out = []
    for rho in dict.fromkeys(r["rho_init"] for r in runs):
        group = [r for r in runs if r["rho_init"] == rho]
        advantage = np.array([r["individuals_mean"] - r["mean_network_mean"] for r in group])
        diversity = np.array([r["individuals_sd"] for r in group])
        out.append(
            {
                "rho_init": rho,
                "sigma_init": group[0]["sigma_init"],
                "advantage": float(advantage.mean()),
                "sem_advantage": seed_sem(advantage),
                "individuals_sd": float(diversity.mean()),
                "sem_individuals_sd": seed_sem(diversity),
                "sigma_trained": float(np.mean([r["sigma_trained"] for r in group])),
                "mean_network_mean": float(np.mean([r["mean_network_mean"] for r in group])),
                "n_seeds": len(group),
            }
        )
    return out


def spread_prose(results: "SpreadResults") -> dict[str, str]:
    """The values chapter 5 says of the spread sweep (its runs and their summary), as text by
    name, for each initial spread k (0 the narrowest): ``spread{k}_sigma`` (trained sigma),
    ``_advantage`` (the
    individuals' mean return less the mean network's, mean +- SEM over seeds), ``_t`` (the
    paired t of each seed), ``_mean_network`` and ``_individuals`` (mean returns), ``_sd``
    (the SD of the individuals' means, mean +- SEM), ``_sigma_change`` (the trained sigma's
    relative change from its start, the largest over seeds, %)."""
    values = {}
    for k, row in enumerate(results.summary):
        group = [r for r in results.runs if r.rho_init == row.rho_init]
        change = max(abs(r.sigma_trained / r.sigma_init - 1.0) for r in group)
        name = f"spread{k}"
        values |= {
            f"{name}_sigma": f"{row.sigma_trained:.2g}",
            f"{name}_advantage": f"{row.advantage:+.0f} ± {row.sem_advantage:.0f}",
            f"{name}_t": ", ".join(f"{r.paired_test.t:+.2f}" for r in group),
            f"{name}_mean_network": f"{row.mean_network_mean:.0f}",
            f"{name}_individuals": f"{np.mean([r.individuals_mean for r in group]):.0f}",
            f"{name}_sd": f"{row.individuals_sd:.0f} ± {row.sem_individuals_sd:.0f}",
            f"{name}_sigma_change": f"{100 * change:.1f} %",
        }
    return values


def run(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Train and evaluate the sweep; write ``rl/spread_<env>_<profile>.json``.

    Each run is kept as a checkpoint in ``out_dir`` and not trained again; the runs at
    the default spread are Figure 3's (64 cell types, our settings).
    """
    if env != "ant":
        raise ValueError(f"env must be 'ant' for spread, got {env!r}")
    recording = start(PROFILES, profile, Path(out_dir) / "rl", f"spread_{env}")
    runs = spread_runs(recording.config, profile, Path(out_dir))
    results = {"env": env, "runs": runs, "summary": summarise_spread(runs)}
    return recording.write(results, recording.config.seeds)


def spread_runs(config: SpreadConfig, profile: str, out_dir: Path) -> list[dict]:
    """Train every (rho_init, seed) of ``config`` on its PPO environment (checkpoints in
    ``out_dir``) and compare each trained genome's individuals with its mean network:
    one record per run."""
    runs = []
    for rho in config.rho_inits:
        ppo = replace(config.ppo, network=replace(config.ppo.network, rho_init=rho))
        cell_types = ppo.network.cell_types
        for seed in config.seeds:
            name = checkpoint_name(ppo.env.name, cell_types, seed, profile, rho_init=rho)
            checkpoint = out_dir / CHECKPOINT_DIR / name
            trained_run(ppo, seed, checkpoint, profile, f"spread rho_init={rho} seed {seed}")
            _, actor, normalizer = load_agent(checkpoint)
            returns = population_on(ppo, actor, normalizer, config.population)
            individuals = returns["normal"]["individuals"].mean(axis=1)
            runs.append(
                {
                    "rho_init": rho,
                    "sigma_init": float(genome.softplus(rho)),
                    "seed": seed,
                    "checkpoint": name,
                    "sigma_trained": genome.mean_sigma(actor),
                    "individuals_mean": float(individuals.mean()),
                    "individuals_sd": float(individuals.std(ddof=1)),
                    "mean_network_mean": float(returns["normal"]["mean_network"].mean()),
                    "paired_test": individuals_vs_mean(returns),
                }
            )
    return runs


PROFILES = {p: spread_config(p) for p in ("smoke", "cpu", "paper")}


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 5 glues of the spreads (``spread_prose``)."""
    return spread_prose(records("spread").results)


def spread_table(payload: "Spread") -> pd.DataFrame:
    """The spread sweep (``sgb.experiments.rl_spread``), one row per run: initial and
    trained sigma, mean returns of the individuals and the mean network, the SD of the
    individuals' returns, and the paired t over individuals with its p."""
    return pd.DataFrame(
        {
            "sigma start": r.sigma_init,
            "seed": r.seed,
            "sigma trained": r.sigma_trained,
            "individuals": r.individuals_mean,
            "mean network": r.mean_network_mean,
            "SD of individuals": r.individuals_sd,
            "paired t(99)": r.paired_test.t,
            "p": r.paired_test.p,
        }
        for r in payload.results.runs
    )


class PairedTest(Record):
    t: Finite
    p: Probability


class SpreadRun(Record):
    rho_init: Finite
    sigma_init: Positive
    seed: Seed
    checkpoint: str
    sigma_trained: NonNegative
    individuals_mean: Return
    individuals_sd: NonNegative
    mean_network_mean: Return
    paired_test: PairedTest


class SpreadSummary(Record):
    """One initial spread over its seeds: the individuals' advantage over their mean
    network and their SD (means, SEMs; null with one seed), the trained sigma."""

    rho_init: Finite
    sigma_init: Positive
    advantage: Finite
    sem_advantage: NonNegative | None
    individuals_sd: NonNegative
    sem_individuals_sd: NonNegative | None
    sigma_trained: NonNegative
    mean_network_mean: Return
    n_seeds: Count


class SpreadResults(Record):
    runs: List[SpreadRun]
    summary: List[SpreadSummary]


class Spread(ResultsFile):
    results: SpreadResults
