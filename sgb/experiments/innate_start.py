"""Chapter 6 (registered as ``innate_start``): is an innate individual a good start for
further learning?

The paper's Discussion proposes to optimise an SGB in one environment, sample individuals
with good zero-shot performance and train those on new tasks "with much less data than
would be required to train them from scratch". Here trained Ant genomes of Figure 3 (64
cell types, seed 0: our settings, the authors' settings, and ours from the wide spread
rho = -3 of the ``spread`` sweep) are fine-tuned with PPO on the long-legged Ant, starting
from

* ``mean``: the genome's mean network;
* ``best``: the best of ``n_individuals`` individuals, chosen by their mean return over
  ``selection_episodes`` episodes on the long-legged Ant (``select``);
* ``random``: a random individual of the same population (individual ``seed``: the
  individuals are independent draws, so a fixed index is a random one);
* ``fresh``: a freshly initialised vanilla network (the same runs for every genome).

The fine-tuned network is a plain vanilla actor of the genome's widths whose weights start
at the developed network's (``sgb.rl.finetune.plain_actor``); its critic and Adam start
fresh (``sgb.rl.ppo.Start``). The ``mean``, ``best`` and ``random`` starts keep the
genome's observation normalizer, which the developed weights expect (a fresh one would
feed them raw observations, on another scale, and undo what the start is meant to hold);
its statistics then keep updating as training goes, the genome's 2M observations of the
normal body still counted beside the long-legged body's. ``fresh`` starts with a fresh
normalizer, as any run from scratch does.

PPO: Figure 3's settings at the profile (``sgb.rl.sweep.sweep_config("ant",
profile)``), on the long-legged body, with ``total_steps`` of the profile and ``num_evals``
evaluations. Seeds pair the runs: fine-tuning seed s gives every start the same critic
initialisation, environment resets and evaluation episodes.

Initial states: selection plays ``population_returns`` with seed ``SELECTION_SEED``; the
fine-tuned runs are scored at step 0 with seed ``seed + START_EVAL_SEED`` and after chunk
i with ``seed + 10_000 + i`` (``sgb.rl.ppo.train``); ``InnateStartConfig`` refuses seeds
that would let the two meet, so the best individual is scored on episodes it was not
chosen on, and its drop from its selection return is the selection's regression to the
mean.

Each run records its evaluation curve (``eval_steps`` with ``eval_returns``, step 0 the
start itself), ``auc`` (the trapezoid area under that curve divided by the steps
trained: the mean return over the budget) and ``return_at`` (the return at each fraction
of ``fractions`` of the budget). The results file (``rl/innate_start_ant_<profile>.json``)
is written after every selection and every run, and a rerun skips what it holds; a run
killed part way continues from its training state (``*.state.npz`` under
``rl/innate_start/``).

Cost (``cpu``), measured on one core with one XLA thread, per CPU-second (the core was
shared, at about 0.73 of it to this process): PPO training of the vanilla network on the
long-legged Ant at Figure 3's cpu settings ran 16,600 env-steps per CPU-second once
compiled (12,100 per wall-second), an evaluation (32 episodes of the vanilla network)
18,100, the selection's population (100 individuals of our 64-type genome) 22,100.
Compiling took about 16 CPU-seconds for the training step, 24 for the evaluation, 12 per
genome network for the selection, and ``sgb.rl.ppo.init_state`` compiles its
environment reset again in every run (about 5.5). The profile is 30 runs (3 genomes x 3
starts x 3 seeds, and 3 fresh) of 4,997,120 steps, 150M steps, about 151 CPU-minutes;
their 30 x 9 evaluations of 32 episodes, 8.6M steps, 8 minutes; 3 selections of 100 x 16
episodes, 4.8M steps, 4 minutes; compiling about 4 minutes: about 2.8 CPU hours in all
(5M steps a run is what fits in 4 hours with room for a slower machine; it is 2.5 times
the 2M steps the genomes were trained for).
"""

import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd
from pydantic import ConfigDict, Field

from sgb import stats, validation
from sgb.claims import Row, judge
from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.prose import NOT_RUN, Card, mean_sem
from sgb.provenance import git_commit
from sgb.recording import Recording, start
from sgb.results import Records
from sgb.rl.agent import NetworkConfig, Params
from sgb.rl.finetune import individual_key, plain_actor, plain_network
from sgb.rl.normalizer import Normalizer, init_normalizer
from sgb.rl.population import population_returns
from sgb.rl.ppo import PPOConfig, Start, evaluate, initial_params, train
from sgb.rl.protocols import load_agent
from sgb.rl.runs import CHECKPOINT_DIR, checkpoint_name, checkpoint_root
from sgb.rl.sweep import sweep_config
from sgb.rl.trainer import make_trainer
from sgb.schemas import (
    Count,
    Finite,
    List,
    NonNegative,
    Record,
    ResultsFile,
    Return,
    Seed,
    Steps,
)
from sgb.stats import sem

STARTS = ("mean", "best", "random", "fresh")
SELECTION_SEED = 20_000  # population_returns' seed of the selection (individuals, states)
START_EVAL_SEED = 30_000  # run seed + this: the seed of a run's step-0 evaluation
TRAIN_EVAL_SEED = 10_000  # run seed + this + i: sgb.rl.ppo.train's evaluation after chunk i


def evaluation_seeds(ppo: PPOConfig, seed: int) -> list[int]:
    """The ``population_returns`` seeds of the evaluations of a run of ``ppo`` with
    ``seed``: at step 0, then after every chunk (``sgb.rl.ppo.train``)."""
    return [seed + START_EVAL_SEED, *(seed + TRAIN_EVAL_SEED + i for i in range(ppo.num_evals))]


@dataclass(frozen=True)
class InnateStartConfig:
    """The genomes (checkpoint files under ``rl/checkpoints``), the fine-tuning PPO (a
    vanilla network of the genomes' widths, on the target body), its seeds, the selection
    (``n_individuals`` x ``selection_episodes`` episodes) and the budget ``fractions`` at
    which returns are read."""

    genomes: tuple[str, ...]
    ppo: PPOConfig
    seeds: tuple[int, ...] = (0, 1, 2)
    n_individuals: int = 100
    selection_episodes: int = 16
    fractions: tuple[float, ...] = (0.0, 0.25, 0.5, 1.0)

    def __post_init__(self) -> None:
        validation.instance("genomes", self.genomes, tuple)
        validation.instance("ppo", self.ppo, PPOConfig)
        if self.ppo.network.sgb:
            raise ValueError("the fine-tuned network is vanilla: ppo.network has no cell types")
        validation.integers("seeds", self.seeds, minimum=0)
        if any(SELECTION_SEED in evaluation_seeds(self.ppo, seed) for seed in self.seeds):
            raise ValueError(f"an evaluation of seeds {self.seeds} would replay the selection's")
        validation.integer("n_individuals", self.n_individuals, minimum=max(self.seeds) + 1)
        validation.integer("selection_episodes", self.selection_episodes)
        for f in self.fractions:
            if not (0.0 <= f <= 1.0 and float(f * self.ppo.num_evals).is_integer()):
                raise ValueError(
                    f"fraction {f} must lie in [0, 1] and fall on an evaluation (a multiple "
                    f"of 1/num_evals = 1/{self.ppo.num_evals})"
                )


def finetune_ppo(profile: str, total_steps: int, num_evals: int) -> PPOConfig:
    """Figure 3's Ant PPO at ``profile`` on the long-legged body, a vanilla network,
    ``total_steps`` env-steps and ``num_evals`` evaluations."""
    ppo = sweep_config("ant", profile).ppo
    return replace(
        ppo,
        env=replace(ppo.env, variant="long_legs"),
        network=plain_network(ppo.network),
        total_steps=total_steps,
        num_evals=num_evals,
    )


def innate_start_config(profile: str) -> InnateStartConfig:
    """The design at ``profile``: at ``smoke`` our committed cpu genome, 8 individuals x 2
    episodes, one seed of 4096 steps; at ``cpu`` the three committed cpu genomes, 100 x 16,
    3 seeds of 5M steps; at ``paper`` Figure 3's paper genomes, 100 x 32, 5 seeds of the
    paper's 5e7 steps."""
    check_profile(profile)
    source = "paper" if profile == "paper" else "cpu"
    genomes = (
        checkpoint_name("ant", 64, 0, source),
        checkpoint_name("ant", 64, 0, source, "authors"),
        checkpoint_name("ant", 64, 0, source, rho_init=-3.0),
    )
    if profile == "smoke":
        ppo = replace(finetune_ppo("smoke", 4096, 4), eval_individuals=4)
        return InnateStartConfig(genomes[:1], ppo, (0,), 8, 2)
    if profile == "cpu":
        return InnateStartConfig(genomes, finetune_ppo("cpu", 5_000_000, 8))
    return InnateStartConfig(
        genomes, finetune_ppo("paper", 50_000_000, 20), (0, 1, 2, 3, 4), 100, 32
    )


PROFILES = {p: innate_start_config(p) for p in PROFILE_NAMES}


def genome_label(checkpoint: str) -> str:
    """A genome's name in the results: its checkpoint file's stem (``ant_k64_s0_cpu``)."""
    return Path(checkpoint).stem


def planned_runs(config: InnateStartConfig) -> list[tuple[str | None, str, int]]:
    """(genome label, start, seed) of every run, seed by seed: the fresh run (genome
    ``None``), then each genome's mean, best and random starts."""
    labels = [genome_label(g) for g in config.genomes]
    return [
        run
        for seed in config.seeds
        for run in [(None, "fresh", seed)]
        + [(label, s, seed) for label in labels for s in STARTS[:-1]]
    ]


def select(
    config: InnateStartConfig, network: NetworkConfig, actor: dict, normalizer: Normalizer
) -> dict:
    """Play ``n_individuals`` of the genome (``network``, ``actor``, ``normalizer``) for
    ``selection_episodes`` episodes each on the target body (seed ``SELECTION_SEED``):
    their mean returns (n_individuals,) and the best one's index and mean return."""
    ppo = config.ppo
    returns = population_returns(
        ppo.env,
        network,
        actor,
        normalizer,
        config.n_individuals,
        config.selection_episodes,
        ppo.episode_length,
        seed=SELECTION_SEED,
    )
    means = returns.mean(axis=1)
    best = int(np.argmax(means))
    return {
        "individual_means": np.round(means, 3).tolist(),
        "best": best,
        "best_selection_return": float(means[best]),
        "population_mean": float(means.mean()),
    }


def curve_scores(
    steps: list[int], returns: list[float], fractions: tuple[float, ...]
) -> dict[str, object]:
    """``auc``: the trapezoid area under the curve (steps, returns) divided by the last
    step (the mean return over the budget); ``return_at``: by fraction f (as text, "0.25"),
    the return of the evaluation at f of the evaluations (f x the last step)."""
    x, y = np.asarray(steps, dtype=float), np.asarray(returns, dtype=float)
    area = float(np.sum(np.diff(x) * (y[1:] + y[:-1]) / 2.0))
    n = len(steps) - 1
    return {
        "auc": area / float(x[-1]),
        "return_at": {f"{f:g}": float(y[round(f * n)]) for f in fractions},
    }


def start_state(ppo: PPOConfig, seed: int, initial: Start | None) -> tuple[Params, Normalizer]:
    """The parameters and normalizer a run of ``ppo`` with ``seed`` starts from, as
    ``sgb.rl.ppo.init_state`` makes them: fresh, with ``initial``'s actor and normalizer."""
    params = initial_params(ppo, seed)
    if initial is None:
        return params, init_normalizer(make_trainer(ppo.step_settings()).agent.obs_size)
    return params._replace(actor=initial.actor), initial.normalizer


def finetune_run(
    config: InnateStartConfig, seed: int, initial: Start | None, state_file: Path
) -> dict:
    """One fine-tuning run from ``initial`` (``None``: fresh): its step-0 evaluation, then
    ``sgb.rl.ppo.train``'s; the curve, its scores, speed and wall time."""
    began = time.perf_counter()
    ppo = config.ppo
    first = evaluate(ppo, *start_state(ppo, seed, initial), seed + START_EVAL_SEED)
    first_s = time.perf_counter() - began
    label = f"innate start {state_file.stem}"
    result = train(ppo, seed, progress=False, state_file=state_file, label=label, initial=initial)
    steps, returns = [0, *result.eval_steps], [first, *result.eval_returns]
    return {
        "eval_steps": steps,
        "eval_returns": returns,
        **curve_scores(steps, returns, config.fractions),
        "train_steps_per_s": result.train_steps_per_s,
        # train's own wall time counts an earlier process's part of a resumed run
        "wall_time_s": round(result.wall_time_s + first_s, 2),
        "git_commit": git_commit(),
    }


class _Genomes:
    """The genomes of a config, loaded once each: their settings, actor and normalizer,
    and their selection records (loaded from the results file, or made and recorded)."""

    def __init__(self, config: InnateStartConfig, out_dir: Path, selections: list[dict]):
        self.config, self.out_dir = config, out_dir
        self.selections = {s["genome"]: s for s in selections}
        self.agents: dict[str, tuple] = {}

    def agent(self, label: str) -> tuple:
        if label not in self.agents:
            relative = str(CHECKPOINT_DIR / f"{label}.msgpack")
            ppo, actor, normalizer = load_agent(checkpoint_root(self.out_dir, relative) / relative)
            if ppo.network.hidden != self.config.ppo.network.hidden:
                raise ValueError(
                    f"genome {label} has hidden widths {ppo.network.hidden}, the fine-tuned "
                    f"network {self.config.ppo.network.hidden}"
                )
            self.agents[label] = (ppo, actor, normalizer)
        return self.agents[label]

    def selection(self, label: str) -> tuple[dict, bool]:
        """The genome's selection record, and whether it was made now."""
        if label in self.selections:
            return self.selections[label], False
        began = time.perf_counter()
        ppo, actor, normalizer = self.agent(label)
        print(f"innate start: selecting among {self.config.n_individuals} of {label}", flush=True)
        record = {"genome": label, **select(self.config, ppo.network, actor, normalizer)}
        record["git_commit"] = git_commit()
        record["wall_time_s"] = round(time.perf_counter() - began, 2)
        self.selections[label] = record
        return record, True

    def initial(self, label: str, start_name: str, seed: int) -> tuple[Start, dict]:
        """The ``Start`` of a genome's ``start_name`` for ``seed`` (its selection made), and
        what its record says of it: the individual's index in the selection population
        (``None`` for the mean network) and that individual's selection return."""
        ppo, actor, normalizer = self.agent(label)
        selection = self.selections[label]
        index = {"best": selection["best"], "random": seed}.get(start_name)
        if index is None:
            return Start(plain_actor(ppo, actor), normalizer), {"individual": None}
        key = individual_key(SELECTION_SEED, self.config.n_individuals, index)
        fields = {"individual": index, "selection_return": selection["individual_means"][index]}
        return Start(plain_actor(ppo, actor, key), normalizer), fields


def summarise(runs: list[dict]) -> list[dict]:
    """Per (genome, start): mean and SEM over seeds (NaN with one) of ``auc`` and of every
    ``return_at``, and of ``auc`` less the fresh run's of the same seed (paired)."""
    fresh = {r["seed"]: r["auc"] for r in runs if r["start"] == "fresh"}
    rows = []
    for genome, start_name in dict.fromkeys((r["genome"], r["start"]) for r in runs):
        group = [r for r in runs if r["genome"] == genome and r["start"] == start_name]
        values = {"auc": [r["auc"] for r in group]}
        for f in group[0]["return_at"]:
            values[f"return_at_{f}"] = [r["return_at"][f] for r in group]
        values["auc_minus_fresh"] = [
            r["auc"] - fresh[r["seed"]] for r in group if r["seed"] in fresh
        ]
        row = {"genome": genome, "start": start_name, "n_seeds": len(group)}
        for name, v in values.items():
            v = np.asarray(v, dtype=float)
            row[name] = float(v.mean()) if v.size else float("nan")
            row[f"{name}_sem"] = float(sem(v)) if v.size > 1 else float("nan")
        rows.append(row)
    return rows


def run(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Select and fine-tune every run of ``profile`` not yet in its results file, writing
    the file after each selection and each run; returns its path."""
    if env != "ant":
        raise ValueError(f"env must be 'ant' for innate_start (long legs), got {env!r}")
    out_dir = Path(out_dir)
    recording = start(PROFILES, profile, out_dir / "rl", f"innate_start_{env}")
    config = recording.config
    earlier = recording.earlier()
    runs = list(earlier.get("runs", []))
    genomes = _Genomes(config, out_dir, list(earlier.get("selections", [])))
    done = {(r["genome"], r["start"], r["seed"]) for r in runs}
    states = out_dir / "rl" / "innate_start"
    for label, start_name, seed in planned_runs(config):
        if (label, start_name, seed) in done:
            continue
        record: dict = {"genome": label, "start": start_name, "seed": seed, "individual": None}
        initial = None
        if label is not None:
            if genomes.selection(label)[1]:  # made now: recorded at once
                _write(recording, genomes, runs)
            initial, fields = genomes.initial(label, start_name, seed)
            record |= fields
        name = f"{label or env + '_vanilla'}_{start_name}_s{seed}_{profile}"
        state_file = states / f"{name}.state.npz"
        state_file.parent.mkdir(parents=True, exist_ok=True)
        print(f"innate start: {name}", flush=True)
        runs.append({**record, **finetune_run(config, seed, initial, state_file)})
        _write(recording, genomes, runs)
        state_file.unlink(missing_ok=True)
    return _write(recording, genomes, runs)


def _write(recording: Recording, genomes: _Genomes, runs: list[dict]) -> Path:
    config = recording.config
    selections = [
        genomes.selections[g] for g in map(genome_label, config.genomes) if g in genomes.selections
    ]
    results = {
        "env": config.ppo.env.name,
        "variant": config.ppo.env.variant,
        "complete": len(runs) == len(planned_runs(config)),
        "selections": selections,
        "runs": runs,
        "summary": summarise(runs),
    }
    return recording.write(results, config.seeds, parts=selections + runs)


def innate_start_rows(results: "InnateStartResults") -> list[Row]:
    """Innate start, then learning on the long-legged Ant (``sgb.experiments.
    innate_start``): per genome and start (mean network, best of 100, random individual),
    the area under its learning curve over the fresh network's of the same seed, less 1;
    a one-sample t over the seeds."""
    runs = results.runs
    fresh = {r.seed: r.auc for r in runs if r.start == "fresh"}
    pool = {len(s.individual_means) for s in results.selections}
    starts = {
        "mean": "its mean network",
        "best": f"the best of {'/'.join(map(str, sorted(pool)))} individuals",
        "random": "a random individual",
    }
    rows = []
    for genome, begin in dict.fromkeys((r.genome, r.start) for r in runs):
        group = [r for r in runs if (r.genome, r.start) == (genome, begin)]
        gains = [r.auc / fresh[r.seed] - 1 for r in group if r.seed in fresh]
        if begin == "fresh" or len(gains) < 2:
            continue
        rows.append(
            judge(
                "ch6.innate_start_rl",
                f"{genome}, from {starts[begin]}",
                stats.one_sample(gains, 0.0),
                f"{len(gains)} seeds of {group[0].eval_steps[-1] / 1e6:.1f}M steps",
            )
        )
    return rows


def innate_start(
    ant: "InnateStart | None", supervised: ResultsFile | None, card: Card
) -> dict[str, str]:
    """Innate start, then learning: what of it is committed (``innate_status``); on the
    Ant, each genome's and start's gain in learning-curve area over the fresh network
    (``innate_rl_rows``: estimate, interval and verdict of ``innate_start_rows``);
    the supervised twin's (an ``innate_start_supervised.InnateStartSupervised`` record):
    its new task (``innate_sup_task``) and its rows of ``card``, each budget's gain of a
    start over the fresh networks (``innate_sup_rows``)."""
    parts = []
    texts = {"innate_rl_rows": NOT_RUN, "innate_sup_task": NOT_RUN, "innate_sup_rows": NOT_RUN}
    if ant is None:
        parts.append(f"the Ant runs {NOT_RUN}")
    else:
        runs = ant.results.runs
        state = "complete" if ant.results.complete else "in progress"
        parts.append(f"{len(runs)} Ant fine-tuning runs committed ({state})")
        rows = innate_start_rows(ant.results)
        if rows:
            texts["innate_rl_rows"] = "; ".join(
                f"{r.setting}: {r.ours}, **{r.verdict}**" for r in rows
            )
    if supervised is None:
        parts.append(f"the supervised twin {NOT_RUN}")
    else:
        summary = supervised.results.summary
        after = ", ".join(
            f"{r.start} {_percent_sem(100 * r.accuracy[-1], r.accuracy_sem[-1], 100)}"
            for r in summary
        )
        parts.append(
            f"the supervised twin on {summary[0].n_seeds} seeds, test accuracy on the new "
            f"task after {summary[0].steps[-1]} steps: {after}"
        )
        rows = card.get("ch6.innate_start_supervised", [])
        if rows:
            texts["innate_sup_task"] = rows[0].setting.split(", from ")[0]
            texts["innate_sup_rows"] = "; ".join(
                f"{r.setting.split(', ', 1)[1]}: {r.ours}, **{r.verdict}**" for r in rows
            )
    return texts | {"innate_status": "; ".join(parts)}


def _percent_sem(mean: float, sem: float | None, scale: float = 1.0) -> str:
    """``mean ± sem %`` (``sem`` times ``scale``), or the mean alone where the SEM is
    missing (``None`` or NaN: one seed)."""
    if sem is None or math.isnan(sem):
        return f"{mean:.1f} %"
    return f"{mean:.1f} ± {scale * sem:.1f} %"


def evidence(records: Records) -> list[Row]:
    """Fine-tuning from an innate start on the Ant (``innate_start_rows``)."""
    payload = records.get("innate_start")
    return [] if payload is None else innate_start_rows(payload.results)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 6 glues of innate starts, on the Ant and supervised (``innate_start``)."""
    return innate_start(records.get("innate_start"), records.get("innate_start_supervised"), card)


def innate_start_table(payload: "InnateStart") -> pd.DataFrame:
    """Learning from an innate start on the long-legged Ant, one row per genome and start,
    means ± SEM over seeds: the return per episode at 0, 1/4, 1/2 and all of the
    fine-tuning, the mean return over it (area under the curve over its steps) and that
    less the fresh network's."""
    rows = []
    for s in payload.results.summary:
        row = {"start": s.start, "genome": s.genome or "none (fresh network)", "seeds": s.n_seeds}
        for at, mean, spread in (
            ("0", s.return_at_0, s.return_at_0_sem),
            ("0.25", s.return_at_0_25, s.return_at_0_25_sem),
            ("0.5", s.return_at_0_5, s.return_at_0_5_sem),
            ("1", s.return_at_1, s.return_at_1_sem),
        ):
            row[f"return at {at}"] = _mean_sem(mean, spread)
        row["mean return over fine-tuning"] = _mean_sem(s.auc, s.auc_sem)
        row["less the fresh network's"] = _mean_sem(s.auc_minus_fresh, s.auc_minus_fresh_sem)
        rows.append(row)
    return pd.DataFrame(rows)


def _mean_sem(mean: float | None, sem: float | None) -> str:
    """``prose.mean_sem`` of a summary's mean and SEM, null (NaN: no runs, one seed) as NaN."""
    return mean_sem(math.nan if mean is None else mean, math.nan if sem is None else sem)


class Selection(Record):
    individual_means: List[Return]


class InnateRun(Record):
    genome: str | None
    start: str
    seed: Seed
    auc: Return
    eval_steps: List[Steps]
    eval_returns: List[Return]


class InnateSummary(Record):
    """A (genome, start)'s means and SEMs over seeds (null: NaN, one seed or no fresh run);
    ``return_at_{f}`` at each fraction f of the fine-tuning (its dot an underscore)."""

    model_config = ConfigDict(serialize_by_alias=True)  # dumped as the file writes it

    genome: str | None
    start: str
    n_seeds: Count
    auc: Return
    auc_sem: NonNegative | None
    return_at_0: Return
    return_at_0_sem: NonNegative | None
    return_at_0_25: Return = Field(alias="return_at_0.25")
    return_at_0_25_sem: NonNegative | None = Field(alias="return_at_0.25_sem")
    return_at_0_5: Return = Field(alias="return_at_0.5")
    return_at_0_5_sem: NonNegative | None = Field(alias="return_at_0.5_sem")
    return_at_1: Return
    return_at_1_sem: NonNegative | None
    auc_minus_fresh: Finite | None
    auc_minus_fresh_sem: NonNegative | None


class InnateStartResults(Record):
    complete: bool
    selections: List[Selection]
    runs: List[InnateRun]
    summary: List[InnateSummary]


class InnateStart(ResultsFile):
    results: InnateStartResults
