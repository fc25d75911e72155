"""Bet-hedging (chapter 6, registered as ``bet_hedging``): do a genome's varied individuals
survive a changing world better than clones of its mean network, and better than a
deterministic lineage?

The paper's abstract: variability "can increase the probability that at least some
individuals will survive in rapidly changing, unpredictable environments". The test is
declared before its runs (``PRIMARY``): a member survives a generation if its return
reaches half of its mean network's mean return on the normal body, and what counts is the
chance that *at least one* of the 100 survives (the abstract's "at least some"), with
"at least 10" and "at least 50" as secondary rows. A survivor is retested: it must reach
the threshold again on an episode from a new initial state (``sgb.hedging``), so that what
survives is ability, not an episode's luck.

The genomes are 64-type Ant genomes trained with Figure 3's PPO settings (the spread
sweep's, ``sgb.experiments.rl_spread``) at two initial spreads, rho = -5 (Figure 3's) and
-3, 15 training seeds each, and a deterministic lineage: the same architecture trained
from rho = ``DETERMINISTIC_RHO``, whose sigma (about 1e-13) lies below float32's
resolution of its weights, so that its individuals play as its mean network does. A
genome not trained yet is trained first (kept as a checkpoint beside the spread sweep's).

Each stochastic genome fields two populations of N members on the four conditions of
``sgb.rl.envs`` (normal, long legs, slippery, low gravity): its individuals, and N clones
of its mean network; the lineage fields its own N members. Member i plays the same 2E
initial states in every population of a genome (``sgb.rl.population.population_returns``,
one seed per genome): the first E choose the survivors, the last E retest them. Actions
are deterministic.

Cost at ``cpu`` (N = 100, E = 5 + 5): 2 x 4 x N x 2E x 1000 = 8M env-steps a stochastic
genome, about 8 CPU-minutes at the 17,000 env-steps per CPU-second of
``population_returns`` on the Ant, half that for a lineage genome, and about 5 CPU-minutes
to train one; 45 genomes, 37 of them to train, about 8 CPU-hours in all. A finished
genome is kept in the results file, written after every genome under a lock, so several
processes share the work (``sgb.grid``).
"""

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from sgb import claims, hedging, runlock, stats, validation
from sgb.claims import CLAIMS, Row, judge, untestable
from sgb.genome import mean_sigma
from sgb.paths import committed_results
from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.prose import NOT_RUN, Card, row_texts
from sgb.provenance import git_commit, results_file
from sgb.queued import Queue, QueuedRun, known_sum
from sgb.recording import Recording, held_results, start
from sgb.results import Records
from sgb.resume import peek
from sgb.rl.envs import VARIANTS
from sgb.rl.population import population_returns
from sgb.rl.ppo import PPOConfig
from sgb.rl.protocols import load_agent
from sgb.rl.runs import CHECKPOINT_DIR, checkpoint_name, finished_run, trained_run
from sgb.rl.sweep import ant_genome_ppo
from sgb.schemas import (
    Each,
    Finite,
    MaybeEmpty,
    NonNegative,
    Probability,
    Record,
    ResultsFile,
    Return,
    Returns,
    Seconds,
    Seed,
)
from sgb.timing import timed

DETERMINISTIC_RHO = -30.0  # sigma = softplus(-30) = 9.4e-14: the deterministic lineage
POPULATIONS = ("individuals", "clones")
QS = (0.25, 0.5, 0.75)  # survival thresholds, shares of the mean network's normal return
KS = (1, 10, 50)  # "at least k survive"
PRIMARY = ("0.5", "1")  # declared before the runs: half the home return, at least one
DECIMALS = 1


@dataclass(frozen=True)
class HedgingConfig:
    """Which genomes (64-type Ant genomes trained with the spread sweep's PPO at
    ``source``, by initial rho, ``DETERMINISTIC_RHO`` for the deterministic lineage, and
    training seed), and how many members, selection episodes (as many again retest) and
    steps; genome j draws its individuals and initial states with seed ``seed + j``."""

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
        """Every (rho_init, training seed), seed by seed, so that every spread grows alike
        while the genomes land."""
        return [(rho, seed) for seed in self.seeds for rho in self.rho_inits]

    def ppo(self, rho_init: float) -> PPOConfig:
        """The training settings of a genome: the spread sweep's at ``source``."""
        return ant_genome_ppo(self.source, rho_init)

    def checkpoint(self, rho_init: float, seed: int) -> str:
        return checkpoint_name("ant", 64, seed, self.source, rho_init=rho_init)


def genome_label(rho_init: float, seed: int) -> str:
    """A genome's name in the progress and the queue: ``rho -3 seed 7``, ``sigma 0 seed 7``."""
    spread = "sigma 0" if rho_init == DETERMINISTIC_RHO else f"rho {rho_init:g}"
    return f"{spread} seed {seed}"


def checkpoint_file(config: HedgingConfig, rho_init: float, seed: int, out_dir: Path) -> Path:
    """A genome's checkpoint: the committed one where it is committed and ``out_dir`` has
    none, else under ``out_dir`` (where it is trained if missing)."""
    relative = Path(CHECKPOINT_DIR) / config.checkpoint(rho_init, seed)
    here, committed = Path(out_dir) / relative, committed_results() / relative
    return committed if committed.exists() and not here.exists() else here


def population_scores(returns: np.ndarray, scale: float, episodes: int) -> dict[str, Any]:
    """One population's scores from its returns (C, N, 2E), the first ``episodes`` of each
    member choosing and the rest retesting: the geometric-mean and arithmetic-mean fitness
    over the C x E selection generations, and ``p_at_least`` and ``p_retested`` (survivors
    who survive again) for every q of ``QS`` and k of ``KS``."""
    chosen, retest = returns[..., :episodes], returns[..., episodes:]
    return {
        "geometric_fitness": hedging.geometric_mean_fitness(chosen, scale),
        "mean_fitness": float(hedging.generation_fitness(chosen, scale).mean()),
        "p_at_least": {
            str(q): {str(k): hedging.p_at_least(chosen, q * scale, k) for k in KS} for q in QS
        },
        "p_retested": {
            str(q): {str(k): hedging.p_at_least(chosen, q * scale, k, retest) for k in KS}
            for q in QS
        },
    }


def run_genome(
    config: HedgingConfig, rho_init: float, seed: int, j: int, checkpoint: Path
) -> dict[str, Any]:
    """Every population of one trained genome on every condition; its record. The scale is
    the mean network's mean return on the normal body over the selection episodes (the
    lineage's own members')."""
    with timed() as spent:
        record = _evaluated(config, rho_init, seed, j, checkpoint)
    return record | spent  # the evaluation's wall and CPU time


def _evaluated(
    config: HedgingConfig, rho_init: float, seed: int, j: int, checkpoint: Path
) -> dict[str, Any]:
    ppo, actor, normalizer = load_agent(checkpoint)
    deterministic = rho_init == DETERMINISTIC_RHO
    populations = POPULATIONS[:1] if deterministic else POPULATIONS
    returns: dict[str, dict[str, np.ndarray]] = {p: {} for p in populations}
    for variant in VARIANTS:
        for population in populations:
            r = population_returns(
                replace(ppo.env, variant=variant),
                ppo.network,
                actor,
                normalizer,
                config.n_individuals,
                2 * config.episodes,
                config.episode_length,
                config.seed + j,
                mean_network=population == "clones",
            )
            returns[population][variant] = np.round(np.asarray(r, np.float64), DECIMALS)
    trained = finished_run(checkpoint, ppo)
    home = populations[-1]  # the clones, or the lineage's members
    scale = round(float(returns[home]["normal"][:, : config.episodes].mean()), DECIMALS + 2)
    return {
        "rho_init": rho_init,
        "training_seed": seed,
        "evaluation_seed": config.seed + j,
        "checkpoint": checkpoint.name,
        "sigma_trained": mean_sigma(actor),
        "training_wall_time_s": trained["wall_time_s"],
        "training_cpu_time_s": trained.get("cpu_time_s"),
        "scale": scale,
        "returns": {p: {v: r.tolist() for v, r in returns[p].items()} for p in populations},
        "scores": {
            p: population_scores(np.stack(list(returns[p].values())), scale, config.episodes)
            for p in populations
        },
        "git_commit": git_commit(),
    }


def run(profile: str, out_dir: Path) -> Path:
    """Train and evaluate every genome of ``profile`` not yet in its results file, one
    process per genome (``sgb.runlock``, on its checkpoint's path under ``out_dir``),
    writing the file after each; returns its path."""
    recording = start(PROFILES, profile, Path(out_dir) / "rl", "bet_hedging_ant")
    config, path = recording.config, recording.path
    plan = config.genomes()
    for j, (rho, seed) in enumerate(plan):
        label = f"bet_hedging {genome_label(rho, seed)} ({j + 1}/{len(plan)})"
        lock = Path(out_dir) / CHECKPOINT_DIR / config.checkpoint(rho, seed)  # the queue's
        with runlock.claim(lock) as mine:
            if not mine:
                print(f"{label}: another process has it", flush=True)
                continue
            if _recorded(recording, rho, seed):
                continue
            checkpoint = checkpoint_file(config, rho, seed, Path(out_dir))
            trained_run(config.ppo(rho), seed, checkpoint, recording.profile, label)
            print(f"{label}: evaluating, {_eta(recording, len(plan) - j)}", flush=True)
            record = run_genome(config, rho, seed, j, checkpoint)
            with runlock.exclusive(path):
                records = [*recording.earlier().get("genomes", []), record]
                _write(recording, records)
    with runlock.exclusive(path):
        return _write(recording, list(recording.earlier().get("genomes", [])))


def _recorded(recording: Recording, rho: float, seed: int) -> bool:
    genomes = recording.earlier().get("genomes", [])
    return any(g["rho_init"] == rho and g["training_seed"] == seed for g in genomes)


def _eta(recording: Recording, left: int) -> str:
    """The time ``left`` more genomes take at the evaluations' mean so far (not counting
    their training)."""
    walls = [g["wall_time_s"] for g in recording.earlier().get("genomes", [])]
    if not walls:
        return "ETA unknown until the first genome ends"
    return f"about {left * np.mean(walls) / 60:.0f} min of evaluation left ({left} genomes)"


def _write(recording: Recording, records: list[dict]) -> Path:
    """The results file with ``records`` in the config's order, and whether all are in."""
    order = {genome: j for j, genome in enumerate(recording.config.genomes())}
    records = sorted(records, key=lambda g: order[(g["rho_init"], g["training_seed"])])
    results = {
        "env": "ant",
        "conditions": list(VARIANTS),
        "selection_episodes": recording.config.episodes,
        "genomes": records,
        "complete": len(records) == len(order),
    }
    return recording.write(results, recording.config.seeds, parts=records)


def queued(profile: str, results_dir: Path) -> Queue:
    """The genomes of ``profile`` under ``results_dir`` in the order they run, for the
    background queue (``sgb.grid``): each one's training chunks, then its evaluation as a
    last chunk; a genome trained here keeps its checkpoint, landed as it appears."""
    config = PROFILES[check_profile(profile)]
    path = results_file(Path(results_dir) / "rl", "bet_hedging_ant", profile)
    genomes = held_results(path, config).get("genomes", [])
    records = {(g["rho_init"], g["training_seed"]): g for g in genomes}
    runs = []
    for rho, seed in config.genomes():
        checkpoint = Path(results_dir) / CHECKPOINT_DIR / config.checkpoint(rho, seed)
        state = checkpoint.with_suffix(".state.npz")
        chunks = config.ppo(rho).num_evals
        trained = checkpoint_file(config, rho, seed, Path(results_dir)).exists()
        progress = peek(state)[1] if not trained and state.exists() else {}
        record = records.get((rho, seed))
        runs.append(
            QueuedRun(
                label=genome_label(rho, seed),
                checkpoint=checkpoint,
                state=state,
                chunks=chunks + 1,
                finished=record is not None,
                wall_time_s=None if record is None else _cost(record, "wall_time_s"),
                chunks_done=chunks if trained else progress.get("chunks", 0),
                spent_s=progress.get("wall_time_s", 0.0),
                cpu_time_s=None if record is None else _cost(record, "cpu_time_s"),
                spent_cpu_s=progress.get("cpu_time_s"),
                kept=(checkpoint, checkpoint.with_suffix(".json")),
            )
        )
    return Queue(path, tuple(runs))


def _cost(record: dict, key: str) -> float | None:
    """A genome's training and evaluation together, in ``key`` (``wall_time_s`` or
    ``cpu_time_s``); None where either was not recorded."""
    return known_sum([record.get(f"training_{key}"), record.get(key)])


def hedging_config(profile: str) -> HedgingConfig:
    """The design at ``profile``: at ``smoke`` one seed at rho = -5 and one of the lineage,
    trained at smoke, N = 50 members (the largest k), 2 + 2 episodes of 50 steps; at
    ``cpu`` rho = -5, -3 and the lineage at 15 seeds each, N = 100, E = 5 + 5 episodes of
    1000 steps; at ``paper`` the same genomes trained at paper, E = 16 + 16."""
    check_profile(profile)
    spreads = (-5.0, -3.0, DETERMINISTIC_RHO)
    if profile == "smoke":
        return HedgingConfig(
            (-5.0, DETERMINISTIC_RHO),
            (0,),
            n_individuals=max(KS),
            episodes=2,
            episode_length=50,
            source="smoke",
        )
    if profile == "cpu":
        return HedgingConfig(spreads, tuple(range(15)))
    return HedgingConfig(spreads, tuple(range(15)), episodes=16, source="paper")


PROFILES = {p: hedging_config(p) for p in PROFILE_NAMES}


def _setting(rho: float, genomes: list, survival: tuple[str, str] | None = None) -> str:
    """The spread's row setting; with ``survival`` = (q, k), the criterion too."""
    sigma = np.mean([g.sigma_trained for g in genomes])
    spread = f"rho from {rho:g} (trained sigma {sigma:.2g})"
    if survival is None:
        return spread
    role = "declared in advance" if survival == PRIMARY else "secondary"
    return f"{spread}, at least {survival[1]} survive ({role})"


def bet_hedging_rows(results: "BetHedgingResults") -> list[Row]:
    """Bet-hedging (``sgb.experiments.bet_hedging``), per initial spread with two genomes or
    more: the chance that at least k retested individuals survive, against clones of
    their mean networks (a one-sample t over the genomes of their differences) for every
    k of ``KS``, the declared one first; the geometric-mean fitness, likewise; and the
    declared survival against the deterministic lineage's members (Welch over genomes)."""
    q, k = PRIMARY
    lineage = [g for g in results.genomes if g.rho_init == DETERMINISTIC_RHO]
    rows = []
    for rho in dict.fromkeys(g.rho_init for g in results.genomes):
        genomes = [g for g in results.genomes if g.rho_init == rho]
        if rho == DETERMINISTIC_RHO or len(genomes) < 2:
            continue
        n, e = np.shape(genomes[0].returns.individuals["normal"])
        episodes = f"({e // 2} + {e // 2} retest) episodes"
        budget = f"{len(genomes)} genomes, {n} members x {episodes} x 4 conditions"
        for each in (k, *(str(other) for other in KS if str(other) != k)):
            survival = [
                g.scores.individuals.p_retested[q][each] - g.scores.clones.p_retested[q][each]
                for g in genomes
            ]
            setting = _setting(rho, genomes, (q, each))
            rows.append(_across_genomes("ch6.hedging_survival", setting, survival, budget))
        geometric = [
            g.scores.individuals.geometric_fitness - g.scores.clones.geometric_fitness
            for g in genomes
        ]
        setting = _setting(rho, genomes)
        rows.append(_across_genomes("ch6.hedging_geometric", setting, geometric, budget))
        if len(lineage) >= 2:
            ours = [g.scores.individuals.p_retested[q][k] for g in genomes]
            theirs = [g.scores.individuals.p_retested[q][k] for g in lineage]
            lineage_budget = f"{budget}; the lineage {len(lineage)} genomes"
            rows.append(_lineage_row(_setting(rho, genomes, PRIMARY), ours, theirs, lineage_budget))
    return rows


def _lineage_row(setting: str, ours: list[float], theirs: list[float], budget: str) -> Row:
    """Individuals against the deterministic lineage by Welch's t; not testable where no
    genome of either differs from the rest."""
    if np.ptp(ours) == 0 and np.ptp(theirs) == 0:
        reason = f"every genome gives {ours[0]:.2f} against {theirs[0]:.2f}: no spread to test"
        return _untestable("ch6.hedging_lineage", setting, reason, budget)
    return judge("ch6.hedging_lineage", setting, stats.welch(ours, theirs), budget)


def _across_genomes(key: str, setting: str, differences, budget: str) -> Row:
    """A one-sample t over the genomes of individuals - clones; not testable where every
    genome gives the same difference (for a survival chance: both populations always, or
    never, had enough survivors)."""
    if np.ptp(differences) == 0:
        reason = f"every genome gives the same difference, {differences[0]:+.2f}: no spread to test"
        return _untestable(key, setting, reason, budget)
    return judge(key, setting, stats.one_sample(differences, 0.0), budget)


def _untestable(key: str, setting: str, reason: str, budget: str) -> Row:
    claim = CLAIMS[key]
    return replace(
        untestable(key, reason),
        setting=setting,
        paper_effect=claim.paper_effect,
        basis=claim.basis,
        budget=budget,
    )


SPREAD_NAMES = {-5.0: "narrow", -3.0: "middle"}


def bet_hedging(payload: "BetHedging | None") -> dict[str, str]:
    """Bet-hedging (``rl/bet_hedging_ant_cpu.json``) as chapter 6 tells it: where the
    design stands (``hedge_status``: the genomes landed per spread and the lineage's, or
    that none has) and, per stochastic spread (``narrow``: rho from -5; ``middle``: -3),
    its trained sigma, its populations' mean returns and its rows in one passage
    (``hedge_{name}``, ``spread_text``), ``NOT_RUN`` until a genome of it has landed."""
    genomes = [] if payload is None else payload.results.genomes
    texts = {"hedge_status": _status(genomes, hedging_config("cpu"))}
    card = claims.by_key(bet_hedging_rows(payload.results)) if genomes else {}
    for rho, name in SPREAD_NAMES.items():
        group = [g for g in genomes if g.rho_init == rho]
        texts[f"hedge_{name}"] = spread_text(rho, group, card) if group else NOT_RUN
    return texts


def _status(genomes: list["HedgingGenome"], config: HedgingConfig) -> str:
    """How far the design has come: each spread's genomes landed and the lineage's."""
    planned = config.genomes()
    if not genomes:
        return (
            f"not yet run: its {len(planned)} genomes ({len(config.seeds)} per spread and of "
            "the lineage) train in the background queue"
        )
    landed = []
    for rho in config.rho_inits:
        group = [g for g in genomes if g.rho_init == rho]
        who = "the lineage" if rho == DETERMINISTIC_RHO else f"rho from {rho:g}"
        landed.append(f"{who} {len(group)} of {len(config.seeds)}")
        if rho == DETERMINISTIC_RHO and group:
            sigma = np.mean([g.sigma_trained for g in group])
            home = np.mean([g.scale for g in group])
            landed[-1] += f" (trained sigma {sigma:.1e}, home return {home:.0f})"
    return f"genomes landed: {'; '.join(landed)}"


ROW_PARTS = {  # a spread's rows in the order the chapter gives them: (claim, setting names)
    "survival": ("ch6.hedging_survival", f"at least {PRIMARY[1]} survive"),
    "lineage": ("ch6.hedging_lineage", ""),
    "k10": ("ch6.hedging_survival", "at least 10 survive"),
    "k50": ("ch6.hedging_survival", "at least 50 survive"),
    "geometric": ("ch6.hedging_geometric", ""),
}


def spread_text(rho: float, group: list["HedgingGenome"], card: Card) -> str:
    """One spread's passage: its trained sigma and mean returns over conditions, members
    and genomes; the declared row (at least one survives, retested: individuals minus
    clones) with the budget that would decide it; against the lineage; the secondary rows
    (at least 10, at least 50, geometric-mean fitness). A row not yet computed (fewer than
    two genomes) reads "not run"."""
    mean_return = {
        p: np.mean([np.mean(list(getattr(g.returns, p).values())) for g in group])
        for p in POPULATIONS
    }
    said = {}
    for part, (key, named) in ROW_PARTS.items():
        row = next(
            (
                r
                for r in card.get(key, [])
                if r.setting.startswith(f"rho from {rho:g} ") and named in r.setting
            ),
            None,
        )
        if row is None:
            said[part] = "not run"
            continue
        found = row_texts("row", row)
        said[part] = f"{found['row_ours']}, {found['row_verdict']}"
        if part == "survival":
            said[part] += f" (would decide: {found['row_decide']})"
    return (
        f"{len(group)} genomes, trained sigma {np.mean([g.sigma_trained for g in group]):.2g}; "
        f"mean returns over the conditions {mean_return['individuals']:.0f} (individuals) and "
        f"{mean_return['clones']:.0f} (clones). At least one survives, retested, individuals "
        f"minus clones: {said['survival']}; against the lineage: {said['lineage']}. "
        f"Secondary: at least 10, {said['k10']}; at least 50, {said['k50']}; "
        f"geometric-mean fitness, {said['geometric']}"
    )


def evidence(records: Records) -> list[Row]:
    """Individuals against clones of the mean network and the lineage (``bet_hedging_rows``)."""
    payload = records.get("bet_hedging")
    return [] if payload is None else bet_hedging_rows(payload.results)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 6 glues of bet-hedging (``bet_hedging``)."""
    return bet_hedging(records.get("bet_hedging"))


def hedging_table(payload: "BetHedging", q: str = PRIMARY[0]) -> pd.DataFrame:
    """Bet-hedging (``sgb.experiments.bet_hedging``), one row per genome and population:
    the trained sigma, the fitness scale (the mean network's mean return at home), the
    geometric mean fitness, and at threshold ``q`` for every k the chance that at least k
    survive and that at least k survive their retest."""
    rows = []
    for g in payload.results.genomes:
        lineage = g.rho_init == DETERMINISTIC_RHO
        for population in POPULATIONS[:1] if lineage else POPULATIONS:
            score = getattr(g.scores, population)
            rows.append(
                {
                    "rho start": g.rho_init,
                    "seed": g.training_seed,
                    "sigma trained": g.sigma_trained,
                    "population": "lineage" if lineage else population,
                    "home return": g.scale,
                    "geometric fitness": score.geometric_fitness,
                    **{f"P(>= {k} survive)": p for k, p in score.p_at_least[q].items()},
                    **{f"P(>= {k} retested)": p for k, p in score.p_retested[q].items()},
                }
            )
    return pd.DataFrame(rows)


class HedgingScore(Record):
    """The survival the scorecard reads: threshold 0.5, at least 1, 10 and 50 members."""

    geometric_fitness: Finite
    mean_fitness: Finite
    p_at_least: Each(Each(Probability, "1", "10", "50"), "0.5")
    p_retested: Each(Each(Probability, "1", "10", "50"), "0.5")


class HedgingReturns(Record):
    individuals: Each(Returns, "normal")
    clones: Each(Returns, "normal") | None = None


class HedgingScores(Record):
    individuals: HedgingScore
    clones: HedgingScore | None = None


class HedgingGenome(Record):
    rho_init: Finite
    training_seed: Seed
    sigma_trained: NonNegative
    training_wall_time_s: Seconds | None = None
    training_cpu_time_s: Seconds | None = None
    scale: Return
    returns: HedgingReturns
    scores: HedgingScores


class BetHedgingResults(Record):
    genomes: MaybeEmpty[HedgingGenome]


class BetHedging(ResultsFile):
    results: BetHedgingResults
