"""Evolution without gradients (chapter 6, registered as ``evolution``): does stochastic
development help a genome that evolution, not gradient descent, shapes?

The paper trains its genomes by gradient descent and states, as a limitation, that
"Darwinian evolution is not differentiable". Here an evolution strategy
(``sgb.evolution``: OpenAI-ES from evosax) evolves the type means of an SGB classifier
from fitness alone, the mean innate accuracy of the networks a candidate genome develops.
The spread is held at one of ``sigmas`` rather than evolved, 0 the deterministic genome,
so that a stochastic genome's individuals differ by design (the variance split of their
test accuracies says by how much), and every genome gets the same number of fitness
evaluations. Each cell evolves one genome at one number of hidden types, spread and seed;
the genomes of a seed start from the same means. Each cell keeps its fitness curves, the
test accuracy of ``eval_individuals`` individuals of its last mean genome and of that
genome's mean network, and the variance split; the summary gives each curve's slope over
its last fifth (has it converged?), and the split along the way: each cell scores its mean
genome on the test set after every tenth of its generations, so that the course of its
individuals' differences shows what evolution does to them.

``run`` writes ``evolution_<dataset>_<profile>.json`` after every cell, atomically, with
provenance; a rerun with the same config skips the cells already there.
"""

import dataclasses
import math
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from sgb import claims, stats, validation
from sgb.cells import train_cells
from sgb.claims import Row, judge
from sgb.compression import compression
from sgb.data import DATASETS, load
from sgb.evolution import EvolutionConfig, evolve
from sgb.profiles import check_profile
from sgb.prose import NOT_RUN, Card, row_of, row_texts
from sgb.provenance import git_commit, results_file
from sgb.queued import Queue, file_run, run_lock
from sgb.recording import Recording, held_results, start
from sgb.results import Records
from sgb.schemas import (
    Accuracy,
    Compression,
    Count,
    Finite,
    List,
    NonNegative,
    Probability,
    Provenance,
    Record,
    ResultsFile,
    Seconds,
    Seed,
)


@dataclasses.dataclass(frozen=True)
class EvolutionSweep:
    """Every (hidden types, spread, seed) of ``base`` on ``dataset``: the hidden layer's
    types are each of ``hidden_types``, the input and output types ``base``'s, the spread
    each of ``sigmas`` (0 first: the deterministic genome every other is compared with)."""

    dataset: str
    base: EvolutionConfig
    hidden_types: tuple[int, ...]
    sigmas: tuple[float, ...]
    seeds: tuple[int, ...]

    def __post_init__(self) -> None:
        validation.choice("dataset", self.dataset, DATASETS)
        validation.instance("base", self.base, EvolutionConfig)
        validation.integers("hidden_types", self.hidden_types, minimum=1)
        validation.distinct("sigmas", validation.reals("sigmas", self.sigmas))
        if self.sigmas[0] != 0 or min(self.sigmas) < 0:
            raise ValueError(f"sigmas must start at 0 and be positive after, got {self.sigmas}")
        validation.integers("seeds", self.seeds, minimum=0)

    def cells(self) -> list[EvolutionConfig]:
        """One config per cell, seed by seed."""
        in_types, _, out_types = self.base.cell_types
        return [
            dataclasses.replace(
                self.base, cell_types=(in_types, k, out_types), sigma=sigma, seed=seed
            )
            for seed in self.seeds
            for k in self.hidden_types
            for sigma in self.sigmas
        ]


def _key(config: EvolutionConfig) -> str:
    """A cell's name in the results file's locks and the queue: ``k8_sigma0.1_s2``."""
    return f"k{config.cell_types[1]}_sigma{config.sigma:g}_s{config.seed}"


def _record_key(record: dict) -> str:
    return f"k{record['hidden_types']}_sigma{record['sigma']:g}_s{record['seed']}"


GENERATIONS = 10_000  # 3000 left 13 of 20 runs rising: CHANGELOG
SIGMAS = (0.0, 0.15, 0.5, 1.5)  # 0: the deterministic genome (a pilot: CHANGELOG)


def run_cell(config: EvolutionConfig, data) -> dict[str, Any]:
    """Evolve one genome (``sgb.evolution.evolve``); a flat record with its compression."""
    began = time.perf_counter()
    in_types, hidden_types, out_types = config.cell_types
    sizes = (data.x_train.shape[1], config.hidden, data.num_classes)
    out_types = data.num_classes if out_types is None else out_types
    in_types = sizes[0] if in_types is None else in_types
    record: dict[str, Any] = {
        "hidden_types": hidden_types,
        "sigma": config.sigma,
        "seed": config.seed,
        "compression": compression("sgb", sizes, hidden_types, in_types, out_types),
        "compression_authors": compression(
            "sgb", sizes, hidden_types, in_types, out_types, "authors"
        ),
        **evolve(config, data),
    }
    record["git_commit"] = git_commit()
    record["wall_time_s"] = round(time.perf_counter() - began, 2)
    return record


def run(profile: str, out_dir: Path, progress: bool = True) -> Path:
    """Evolve every cell of ``profile`` that no other process holds and no run has
    finished, writing the results file with provenance after each."""
    recording = start(PROFILES, profile, out_dir, lambda sweep: f"evolution_{sweep.dataset}")
    sweep, path = recording.config, recording.path
    data = load(sweep.dataset, seed=0)

    def held() -> list[dict]:
        return list(recording.earlier().get("records", []))

    return train_cells(
        path,
        sweep.cells(),
        held(),
        (_key, _record_key),
        lambda cell: run_cell(cell, data),
        lambda records: _write(recording, records),
        f"evolution {sweep.dataset}",
        progress,
        shared=(lambda cell: run_lock(path, _key(cell)), held),
    )


def queued(profile: str, results_dir: Path) -> Queue:
    """The cells of ``profile`` under ``results_dir`` in the order they evolve (each one
    chunk: a cell is not resumable), for the background queue (``sgb.grid``)."""
    sweep = PROFILES[check_profile(profile)]
    path = results_file(results_dir, f"evolution_{sweep.dataset}", profile)
    done = {_record_key(r): r for r in held_results(path, sweep).get("records", [])}
    runs = []
    for cell in sweep.cells():
        label = f"sigma {cell.sigma:g} seed {cell.seed}"
        runs.append(file_run(label, path, _key(cell), done.get(_key(cell))))
    return Queue(path, tuple(runs))


def _write(recording: Recording, records: list[dict]) -> Path:
    order = {_key(cell): j for j, cell in enumerate(recording.config.cells())}
    records = sorted(records, key=lambda r: order[_record_key(r)])
    results = {
        "dataset": recording.config.dataset,
        "records": records,
        "convergence": [convergence(r) for r in records],
    }
    return recording.write(results, recording.config.seeds, parts=records)


CONVERGED_SHARE = 0.2  # the last fifth of the generations
# A run still rises if its fitness gains more than this over its last fifth, in points per
# 1,000 generations: a point more from 1,000 generations more. (A fitness curve's steps are
# correlated, so the least-squares interval is too narrow to say it.)
RISING = 1.0


def convergence(record: dict) -> dict[str, Any]:
    """The slope of a cell's mean fitness over its last ``CONVERGED_SHARE`` of generations,
    in accuracy points per 1,000 generations, with its 95 % interval (a least-squares
    line, ``sgb.stats.slope``)."""
    fitness = 100 * np.asarray(record["mean_fitness"])
    start = int(len(fitness) * (1 - CONVERGED_SHARE))
    test = stats.slope(np.arange(start, len(fitness)) / 1000, fitness[start:])
    return {
        "hidden_types": record["hidden_types"],
        "sigma": record["sigma"],
        "seed": record["seed"],
        "slope": test.estimate,
        "slope_ci": [test.low, test.high],
    }


PROFILES: dict[str, EvolutionSweep] = {
    "smoke": EvolutionSweep(
        "digits",
        EvolutionConfig(
            hidden=16,
            cell_types=(None, 2, None),
            candidates=16,
            individuals=4,
            generations=20,
            batch_size=128,
            eval_individuals=10,
            scorings=2,
        ),
        hidden_types=(2,),
        sigmas=(0.0, 0.1),
        seeds=(0,),
    ),
    "cpu": EvolutionSweep(
        "digits",
        EvolutionConfig(cell_types=(None, 8, None), generations=GENERATIONS, scorings=10),
        hidden_types=(8,),
        sigmas=SIGMAS,
        seeds=(0, 1, 2, 3, 4),
    ),
    "paper": EvolutionSweep(
        "fashion-mnist",
        EvolutionConfig(
            hidden=64, cell_types=(None, 8, None), generations=4 * GENERATIONS, scorings=10
        ),
        hidden_types=(8,),
        sigmas=SIGMAS,
        seeds=(0, 1, 2, 3, 4),
    ),
}


def evolution_rows(results: "EvolutionResults") -> list[Row]:
    """Evolution without gradients (``sgb.experiments.evolution``): per number of hidden
    types and spread sigma > 0, the genome's individuals (their mean test accuracy)
    against the deterministic genome's network, paired by seed (both start from the same
    means), in points."""
    records = results.records
    rows = []
    for k in sorted({r.hidden_types for r in records}):
        by_sigma = {}
        for r in records:
            if r.hidden_types == k:
                by_sigma.setdefault(r.sigma, {})[r.seed] = r
        deterministic = by_sigma.get(0.0, {})
        for sigma, cells in sorted(by_sigma.items()):
            seeds = sorted(set(cells) & set(deterministic))
            if sigma == 0 or len(seeds) < 2:
                continue
            first = cells[seeds[0]]
            rows.append(
                judge(
                    "ch6.evolution_stochastic_helps",
                    f"{results.dataset}, {k} hidden types ({first.compression:.0f}x), "
                    f"sigma {sigma:g}",
                    stats.paired(
                        [100 * np.mean(cells[s].individuals) for s in seeds],
                        [100 * deterministic[s].mean_network for s in seeds],
                    ),
                    f"{len(first.mean_fitness)} generations, {len(seeds)} seeds",
                )
            )
    return rows


def evolution(payload: "Evolution | None") -> dict[str, str]:
    """Evolution without gradients (``evolution_digits_cpu.json``): the design
    (``evo_design``), the deterministic genome's test accuracy (``evo_deterministic``,
    mean +- SEM over seeds), the slopes of the fitness over the last fifth
    (``evo_slopes``), the runs still rising by more than ``RISING`` (``evo_rising``), and
    per spread j of ``SIGMAS`` past 0 its sigma (``evo_s{j}``), its
    individuals' test accuracy (``evo_s{j}_individuals``), how much they differ
    (``evo_s{j}_split``: the runs whose individuals differ by the F-test, and the variance
    split's medians over seeds), how that moved from the first scoring along the way to
    the last (``evo_s{j}_course``) and its row of
    ``evolution_rows`` (``evo_s{j}_*``); ``NOT_RUN`` for all without the file."""
    texts = {"evo_design": NOT_RUN, "evo_deterministic": NOT_RUN, "evo_slopes": NOT_RUN}
    texts["evo_rising"] = NOT_RUN
    for j, sigma in enumerate(SIGMAS[1:], 1):
        texts[f"evo_s{j}"] = f"{sigma:g}"
        texts |= {f"evo_s{j}_{g}": NOT_RUN for g in ("individuals", "split", "course")}
        texts |= row_texts(f"evo_s{j}", None)
    if payload is None:
        return texts
    records = payload.results.records
    base = payload.provenance.config.base
    texts["evo_design"] = (
        f"{len(records[0].mean_fitness)} generations of {base.candidates} candidate genomes, "
        f"each scored by {base.individuals} networks on {base.individuals} batches, "
        f"{len({r.seed for r in records})} seeds"
    )
    convergence = payload.results.convergence
    slopes = [c.slope for c in convergence]
    texts["evo_slopes"] = f"{min(slopes):+.2f} to {max(slopes):+.2f}"
    rising = [c for c in convergence if c.slope > RISING]
    by_sigma = ", ".join(
        f"{sum(c.sigma == sigma for c in rising)} of {sum(c.sigma == sigma for c in convergence)} "
        f"at sigma {sigma:g}"
        for sigma in dict.fromkeys(c.sigma for c in convergence)
    )
    texts["evo_rising"] = f"{len(rising)} of {len(convergence)} runs ({by_sigma})"
    texts["evo_deterministic"] = _mean_sem([100 * r.mean_network for r in records if r.sigma == 0])
    card = claims.by_key(evolution_rows(payload.results))
    for j, sigma in enumerate(SIGMAS[1:], 1):
        cells = [r for r in records if r.sigma == sigma]
        if not cells:
            continue
        texts[f"evo_s{j}_individuals"] = _mean_sem([100 * np.mean(r.individuals) for r in cells])
        splits = [r.variance_split for r in cells]
        differ, between = _how_they_differ(splits)
        within = 100 * np.median([v.within_sd for v in splits])
        texts[f"evo_s{j}_split"] = (
            f"its individuals differ measurably (F-test, p < 0.05) in {differ} of "
            f"{len(splits)} runs, by an SD of {between:.1f} points, against {within:.1f} "
            f"between parts of the test set (ICC {np.median([v.icc for v in splits]):.2f}; "
            "medians over the runs)"
        )
        texts[f"evo_s{j}_course"] = _course_text(cells)
        texts |= row_texts(
            f"evo_s{j}", row_of(card, "ch6.evolution_stochastic_helps", f"sigma {sigma:g}")
        )
    return texts


def _course_text(cells: list["EvolutionRecord"]) -> str:
    """How the individuals' differences moved over the runs ``cells`` of one spread: the
    runs whose individuals differ measurably (F-test, p < 0.05) at the first scoring and
    at the last, and the median SD between them (0 where all score alike); ``NOT_RUN``
    where the runs were not scored along the way."""
    if any(c.course is None or len(c.course) < 2 for c in cells):
        return f"{NOT_RUN} (these runs were scored at their end only)"

    (a, s1), (b, s2) = (
        _how_they_differ([c.course[i].variance_split for c in cells]) for i in (0, -1)
    )
    g1, g2 = (cells[0].course[i].generation for i in (0, -1))
    return (
        f"its individuals differ measurably (F-test, p < 0.05) in {a} of {len(cells)} runs "
        f"after {g1:,} generations and in {b} after {g2:,}; the median SD between them "
        f"{s1:.1f} points, then {s2:.1f}"
    )


def _how_they_differ(splits: list["VarianceSplitRecord | None"]) -> tuple[int, float]:
    """Of one spread's runs, those whose individuals differ measurably (F-test, p < 0.05)
    and the median SD between individuals in accuracy points; a split of ``None`` (every
    individual scored alike) counts as no difference, an SD of 0."""
    differ = sum(v is not None and v.p < 0.05 for v in splits)
    between = np.median([0.0 if v is None else 100 * v.between_sd for v in splits])
    return differ, float(between)


def _mean_sem(values: list[float]) -> str:
    values = np.asarray(values)
    if values.size < 2:
        return f"{values.mean():.1f} %"
    return f"{values.mean():.1f} ± {values.std(ddof=1) / math.sqrt(values.size):.1f} %"


def evidence(records: Records) -> list[Row]:
    """Each stochastic genome against the deterministic one (``evolution_rows``)."""
    payload = records.get("evolution")
    return [] if payload is None else evolution_rows(payload.results)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 6 glues of evolution (``evolution``)."""
    return evolution(records.get("evolution"))


def evolution_table(payload: "Evolution") -> pd.DataFrame:
    """Evolution without gradients (``sgb.experiments.evolution``), one row per cell:
    hidden types, compression (ours), sigma, seed, the last generation's mean fitness and
    the slope over the last fifth (points per 1,000 generations), the test accuracy (%) of
    the evolved genome's individuals (their mean and SD, in points) and of its mean
    network, the individuals' ICC over parts of the test set, and the wall time."""
    slopes = {(c.hidden_types, c.sigma, c.seed): c.slope for c in payload.results.convergence}
    return pd.DataFrame(
        {
            "hidden types": r.hidden_types,
            "compression": r.compression,
            "sigma": r.sigma,
            "seed": r.seed,
            "last fitness": r.mean_fitness[-1],
            "slope, last fifth": slopes[(r.hidden_types, r.sigma, r.seed)],
            "individuals (% accuracy)": 100 * float(np.mean(r.individuals)),
            "SD of individuals (points)": 100 * float(np.std(r.individuals, ddof=1)),
            "mean network (% accuracy)": 100 * r.mean_network,
            "ICC": math.nan if r.variance_split is None else r.variance_split.icc,
            "wall time (s)": r.wall_time_s,
        }
        for r in payload.results.records
    )


class VarianceSplitRecord(Record):
    between_sd: NonNegative
    within_sd: NonNegative
    icc: Finite
    p: Probability


class Scoring(Record):
    """The mean genome scored on the test set part-way (``sgb.evolution.evolve``)."""

    generation: Count
    accuracy: Accuracy  # its individuals' mean
    mean_network: Accuracy
    variance_split: VarianceSplitRecord | None = None


class EvolutionRecord(Record):
    hidden_types: Count
    sigma: NonNegative
    seed: Seed
    compression: Compression
    mean_fitness: List[Accuracy]
    individuals: List[Accuracy]
    mean_network: Accuracy
    variance_split: VarianceSplitRecord | None = None
    course: List[Scoring] | None = None  # absent from runs made before it was scored
    wall_time_s: Seconds


class Convergence(Record):
    hidden_types: Count
    sigma: NonNegative
    seed: Seed
    slope: Finite
    slope_ci: List[Finite]


class EvolutionResults(Record):
    dataset: str
    records: List[EvolutionRecord]
    convergence: List[Convergence]


class Candidates(Record):
    candidates: Count
    individuals: Count


class SweepConfig(Record):
    base: Candidates


class EvolutionProvenance(Provenance):
    config: SweepConfig


class Evolution(ResultsFile):
    provenance: EvolutionProvenance
    results: EvolutionResults
