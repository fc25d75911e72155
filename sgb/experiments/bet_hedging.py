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
import pandas as pd

from sgb import claims, hedging, stats, validation
from sgb.claims import CLAIMS, Row, judge, untestable
from sgb.genome import mean_sigma
from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.prose import NOT_RUN, Card, row_of, row_texts
from sgb.provenance import git_commit
from sgb.recording import Recording, start
from sgb.results import Records
from sgb.rl.envs import VARIANTS
from sgb.rl.population import population_returns
from sgb.rl.protocols import load_agent
from sgb.rl.runs import checkpoint_name, checkpoint_root
from sgb.schemas import (
    Each,
    Finite,
    List,
    NonNegative,
    Probability,
    Record,
    ResultsFile,
    Return,
    Returns,
    Seed,
)

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


HEDGING_Q = "0.5"  # survival: a return of half the mean network's on the normal body


HEDGING_K = "10"  # at least 10 of the 100 members


def bet_hedging_rows(results: "BetHedgingResults") -> list[Row]:
    """Bet-hedging (``sgb.experiments.bet_hedging``): per initial spread, the genomes'
    individuals against clones of their mean networks on the four conditions, by
    geometric-mean fitness and by the chance that at least ``HEDGING_K`` of them survive
    (a return of ``HEDGING_Q`` of the mean network's on the normal body); a one-sample t
    over the genomes of their differences."""
    rows = []
    for rho in dict.fromkeys(g.rho_init for g in results.genomes):
        genomes = [g for g in results.genomes if g.rho_init == rho]
        if len(genomes) < 2:
            continue
        scores = [g.scores for g in genomes]
        sigma = np.mean([g.sigma_trained for g in genomes])
        setting = f"rho from {rho:g} (trained sigma {sigma:.2g})"
        n, e = np.shape(genomes[0].returns.individuals["normal"])
        budget = f"{len(genomes)} genomes, {n} members x {e} episodes x 4 conditions"
        geometric = [s.individuals.geometric_fitness - s.clones.geometric_fitness for s in scores]
        rows.append(_across_genomes("ch6.hedging_geometric", setting, geometric, budget))
        survival = [
            s.individuals.p_at_least[HEDGING_Q][HEDGING_K]
            - s.clones.p_at_least[HEDGING_Q][HEDGING_K]
            for s in scores
        ]
        rows.append(_across_genomes("ch6.hedging_survival", setting, survival, budget))
    return rows


def _across_genomes(key: str, setting: str, differences, budget: str) -> Row:
    """A one-sample t over the genomes of individuals - clones; not testable where every
    genome gives the same difference (for a survival chance: both populations always, or
    never, had enough survivors)."""
    if np.ptp(differences) == 0:
        reason = f"every genome gives the same difference, {differences[0]:+.2f}: no spread to test"
        claim = CLAIMS[key]
        return replace(
            untestable(key, reason),
            setting=setting,
            paper_effect=claim.paper_effect,
            basis=claim.basis,
            budget=budget,
        )
    return judge(key, setting, stats.one_sample(differences, 0.0), budget)


def bet_hedging(payload: "BetHedging | None") -> dict[str, str]:
    """Bet-hedging (``rl/bet_hedging_ant_cpu.json``): the design (``hedge_design``) and, per
    initial spread j (0 the narrowest: rho from -5, -3, -1.5), its trained sigma
    (``hedge{j}_sigma``), both populations' mean return over conditions, members and
    genomes (``hedge{j}_returns``) and the rows of ``bet_hedging_rows``:
    geometric-mean fitness (``hedge{j}_geometric_*``) and survival
    (``hedge{j}_survival_*``); ``NOT_RUN`` for all without the file."""
    texts = {"hedge_design": NOT_RUN}
    for j in range(3):
        texts[f"hedge{j}_sigma"] = texts[f"hedge{j}_returns"] = NOT_RUN
        texts |= row_texts(f"hedge{j}_geometric", None) | row_texts(f"hedge{j}_survival", None)
    if payload is None:
        return texts
    genomes = payload.results.genomes
    card = claims.by_key(bet_hedging_rows(payload.results))
    for j, rho in enumerate(dict.fromkeys(g.rho_init for g in genomes)):
        group = [g for g in genomes if g.rho_init == rho]
        texts[f"hedge{j}_sigma"] = f"{np.mean([g.sigma_trained for g in group]):.2g}"
        populations = {
            "individuals": [g.returns.individuals for g in group],
            "clones": [g.returns.clones for g in group],
        }
        mean_return = {
            p: np.mean([np.mean(list(r.values())) for r in returns])
            for p, returns in populations.items()
        }
        texts[f"hedge{j}_returns"] = (
            f"{mean_return['individuals']:.0f} for the individuals, "
            f"{mean_return['clones']:.0f} for the clones"
        )
        for kind in ("geometric", "survival"):
            row = row_of(card, f"ch6.hedging_{kind}", f"rho from {rho:g} ")
            texts |= row_texts(f"hedge{j}_{kind}", row)
            texts["hedge_design"] = NOT_RUN if row is None else row.budget
    return texts


def evidence(records: Records) -> list[Row]:
    """Individuals against clones of the mean network (``bet_hedging_rows``)."""
    payload = records.get("bet_hedging")
    return [] if payload is None else bet_hedging_rows(payload.results)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 6 glues of bet-hedging (``bet_hedging``)."""
    return bet_hedging(records.get("bet_hedging"))


def hedging_table(payload: "BetHedging", q: str = "0.5") -> pd.DataFrame:
    """Bet-hedging (``sgb.experiments.bet_hedging``), one row per genome and population:
    the trained sigma, the fitness scale (the mean network's mean return at home), the
    geometric and arithmetic mean fitness, and P(at least k survive) at threshold ``q``
    for every k."""
    rows = []
    for g in payload.results.genomes:
        for population, score in (
            ("individuals", g.scores.individuals),
            ("clones", g.scores.clones),
        ):
            rows.append(
                {
                    "rho start": g.rho_init,
                    "seed": g.training_seed,
                    "sigma trained": g.sigma_trained,
                    "population": population,
                    "home return": g.scale,
                    "geometric fitness": score.geometric_fitness,
                    "mean fitness": score.mean_fitness,
                    **{f"P(>= {k} survive)": p for k, p in score.p_at_least[q].items()},
                }
            )
    return pd.DataFrame(rows)


class HedgingScore(Record):
    """The survival the scorecard reads: threshold 0.5, at least 10 members."""

    geometric_fitness: Finite
    mean_fitness: Finite
    p_at_least: Each(Each(Probability, "10"), "0.5")


class HedgingReturns(Record):
    individuals: Each(Returns, "normal")
    clones: Each(Returns, "normal")


class HedgingScores(Record):
    individuals: HedgingScore
    clones: HedgingScore


class HedgingGenome(Record):
    rho_init: Finite
    training_seed: Seed
    sigma_trained: NonNegative
    scale: Return
    returns: HedgingReturns
    scores: HedgingScores


class BetHedgingResults(Record):
    genomes: List[HedgingGenome]


class BetHedging(ResultsFile):
    results: BetHedgingResults
