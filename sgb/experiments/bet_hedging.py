"""Bet-hedging (chapter 6, registered as ``bet_hedging``): do a genome's varied individuals
survive a changing world better than clones of its mean network?

The paper's abstract: variability "can increase the probability that at least some
individuals will survive in rapidly changing, unpredictable environments". Here each
trained 64-type Ant genome of the spread sweep (``sgb.experiments.rl_spread``: initial
spreads rho = -5, -3 and -1.5, seeds 0 to 2) fields two populations of N members on the
four conditions of ``sgb.rl.envs`` (normal, long legs, slippery, low gravity): its
individuals, and N clones of its mean network. Member i plays the same E initial states in
both populations (``sgb.rl.population.population_returns`` with one seed per genome), so
the clones differ only by their initial states. Actions are deterministic.

Each genome's record keeps every return, (N, E) per population and condition, and its
scores (``sgb.hedging``): the geometric-mean fitness of each population over the 4 x E
generations (fitness in units of the mean network's mean return on the normal body) and
the probability that at least k of the N survive, a member surviving if its return reaches
a share q of that same return, for every k of ``KS`` and q of ``QS``.

Cost: 2 x 4 x N x E x 1000 env-steps a genome, 4M at ``cpu`` (N = 100, E = 5): about
4 CPU-minutes at the 17,000 env-steps per CPU-second of ``population_returns`` on the Ant
(``sgb.experiments.populations``), 36 for the 9 genomes, plus about 25 CPU-seconds to
compile each of the 8 programs (4 conditions x 2 populations). A finished genome is kept
in the results file, written after every genome, and not evaluated again on a rerun.
"""

import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from sgb import hedging, validation
from sgb.genome import mean_sigma
from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.provenance import git_commit
from sgb.recording import Recording, start
from sgb.rl.envs import VARIANTS
from sgb.rl.population import population_returns
from sgb.rl.protocols import load_agent
from sgb.rl.runs import checkpoint_name, checkpoint_root

POPULATIONS = ("individuals", "clones")
QS = (0.25, 0.5, 0.75)  # survival thresholds, shares of the mean network's normal return
KS = (1, 10, 50)  # "at least k survive"
DECIMALS = 3


@dataclass(frozen=True)
class HedgingConfig:
    """Which genomes (64-type checkpoints of the spread sweep at ``source``, by initial
    rho and training seed, each listed once), and how many members, episodes and steps;
    genome j draws its individuals and initial states with seed ``seed + j``, a seed of
    ``sgb.validation.seed`` for every j."""

    rho_inits: tuple[float, ...]
    seeds: tuple[int, ...]
    n_individuals: int = 100
    episodes: int = 5
    episode_length: int = 1000
    seed: int = 0
    source: str = "cpu"

    def __post_init__(self) -> None:
        validation.distinct("rho_inits", validation.reals("rho_inits", self.rho_inits))
        validation.distinct("seeds", validation.integers("seeds", self.seeds, minimum=0))
        validation.integer("n_individuals", self.n_individuals, minimum=max(KS))
        validation.integer("episodes", self.episodes)
        validation.integer("episode_length", self.episode_length)
        last = len(self.genomes()) - 1
        if validation.seed("seed", self.seed) + last >= 2**32:
            raise ValueError(
                f"seed + j must be < 2**32 for every genome j up to {last}, got seed={self.seed}"
            )
        validation.choice("source", self.source, PROFILE_NAMES)

    def genomes(self) -> list[tuple[float, int]]:
        """Every (rho_init, training seed), spread by spread."""
        return [(rho, seed) for rho in self.rho_inits for seed in self.seeds]

    def checkpoint(self, rho_init: float, seed: int) -> str:
        return checkpoint_name("ant", 64, seed, self.source, rho_init=rho_init)


def scores(individuals: np.ndarray, clones: np.ndarray, scale: float) -> dict[str, Any]:
    """Both populations' scores from their returns (C, N, E) and the fitness ``scale``: the
    geometric-mean fitness, the arithmetic mean of the generations' fitness, and
    ``p_at_least[q][k]`` for every q of ``QS`` and k of ``KS``."""
    out: dict[str, Any] = {}
    for name, returns in zip(POPULATIONS, (individuals, clones), strict=True):
        out[name] = {
            "geometric_fitness": hedging.geometric_mean_fitness(returns, scale),
            "mean_fitness": float(hedging.generation_fitness(returns, scale).mean()),
            "p_at_least": {
                str(q): {str(k): hedging.p_at_least(returns, q * scale, k) for k in KS} for q in QS
            },
        }
    return out


def run_genome(config: HedgingConfig, rho_init: float, seed: int, j: int, out_dir: Path) -> dict:
    """Both populations of one genome on every condition; its record."""
    began = time.perf_counter()
    name = config.checkpoint(rho_init, seed)
    path = checkpoint_root(out_dir, f"rl/checkpoints/{name}") / "rl" / "checkpoints" / name
    ppo, actor, normalizer = load_agent(path)
    returns = {population: {} for population in POPULATIONS}
    for variant in VARIANTS:
        common = (
            replace(ppo.env, variant=variant),
            ppo.network,
            actor,
            normalizer,
            config.n_individuals,
            config.episodes,
            config.episode_length,
            config.seed + j,
        )
        for population in POPULATIONS:
            r = population_returns(*common, mean_network=population == "clones")
            returns[population][variant] = np.round(r, DECIMALS)
    scale = float(returns["clones"]["normal"].mean())
    stacked = {p: np.stack([returns[p][v] for v in VARIANTS]) for p in POPULATIONS}
    return {
        "rho_init": rho_init,
        "training_seed": seed,
        "evaluation_seed": config.seed + j,
        "checkpoint": name,
        "sigma_trained": mean_sigma(actor),
        "scale": scale,
        "returns": {p: {v: r.tolist() for v, r in returns[p].items()} for p in POPULATIONS},
        "scores": scores(stacked["individuals"], stacked["clones"], scale),
        "git_commit": git_commit(),
        "wall_time_s": round(time.perf_counter() - began, 2),
    }


def run(profile: str, out_dir: Path) -> Path:
    """Evaluate every genome of ``profile`` not yet in its results file, writing the file
    with provenance after each."""
    recording = start(PROFILES, profile, Path(out_dir) / "rl", "bet_hedging_ant")
    config = recording.config
    records = list(recording.earlier().get("genomes", []))
    done = {(r["rho_init"], r["training_seed"]) for r in records}
    for j, (rho, seed) in enumerate(config.genomes()):
        if (rho, seed) in done:
            continue
        print(f"bet_hedging ({profile}): genome rho_init={rho:g} seed {seed}", flush=True)
        records.append(run_genome(config, rho, seed, j, Path(out_dir)))
        _write(recording, records)
    if not recording.path.exists():
        _write(recording, records)
    return recording.path


def _write(recording: Recording, records: list[dict]) -> Path:
    results = {"env": "ant", "conditions": list(VARIANTS), "genomes": records}
    return recording.write(results, recording.config.seeds, parts=records)


def hedging_config(profile: str) -> HedgingConfig:
    """The design at ``profile``: at ``smoke`` the seed-0 genomes of the narrowest and
    widest spreads, N = 50 members (the largest k), 2 episodes of 50 steps; at ``cpu`` 9
    genomes, N = 100, E = 5 episodes of 1000 steps; at ``paper`` 5 seeds, E = 16."""
    check_profile(profile)
    if profile == "smoke":
        return HedgingConfig(
            (-5.0, -1.5), (0,), n_individuals=max(KS), episodes=2, episode_length=50
        )
    if profile == "cpu":
        return HedgingConfig((-5.0, -3.0, -1.5), (0, 1, 2))
    return HedgingConfig((-5.0, -3.0, -1.5), (0, 1, 2, 3, 4), episodes=16, source="paper")


PROFILES = {p: hedging_config(p) for p in PROFILE_NAMES}
