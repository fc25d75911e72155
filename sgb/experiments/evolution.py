"""Evolution without gradients (chapter 6, registered as ``evolution``): does stochastic
development help a genome that evolution, not gradient descent, shapes?

The paper trains its genomes by gradient descent and argues that the mechanism should hold
although "Darwinian evolution is not differentiable". Here an evolution strategy
(``sgb.evolution``: OpenAI-ES from evosax) evolves the type tables of an SGB classifier
from fitness alone, the mean innate accuracy of the individuals a candidate genome
develops. Each cell evolves one genome at one number of hidden types (a compression
ratio) and seed, either stochastic (means and spreads evolved, ``individuals`` networks
scored per candidate) or deterministic (sigma = 0: the means alone, one network per
candidate); the two settings of a seed start from the same means. Each cell keeps its
fitness curves and the test accuracy of ``eval_individuals`` individuals of its last mean
genome and of that genome's mean network.

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
from sgb.prose import NOT_RUN, Card, row_of, row_texts
from sgb.provenance import git_commit
from sgb.recording import Recording, start
from sgb.results import Records
from sgb.schemas import (
    Accuracy,
    Compression,
    Count,
    List,
    NonNegative,
    Provenance,
    Record,
    ResultsFile,
    Seconds,
    Seed,
)


@dataclasses.dataclass(frozen=True)
class EvolutionSweep:
    """Every (hidden types, seed, stochastic or not) of ``base`` on ``dataset``: the hidden
    layer's types are each of ``hidden_types``, the input and output types ``base``'s."""

    dataset: str
    base: EvolutionConfig
    hidden_types: tuple[int, ...]
    seeds: tuple[int, ...]

    def __post_init__(self) -> None:
        validation.choice("dataset", self.dataset, DATASETS)
        validation.instance("base", self.base, EvolutionConfig)
        validation.integers("hidden_types", self.hidden_types, minimum=1)
        validation.integers("seeds", self.seeds, minimum=0)

    def cells(self) -> list[EvolutionConfig]:
        """One config per cell, seed by seed, stochastic first."""
        in_types, _, out_types = self.base.cell_types
        return [
            dataclasses.replace(
                self.base, cell_types=(in_types, k, out_types), stochastic=stochastic, seed=seed
            )
            for seed in self.seeds
            for k in self.hidden_types
            for stochastic in (True, False)
        ]


def _key(config: EvolutionConfig) -> tuple[int, bool, int]:
    return config.cell_types[1], config.stochastic, config.seed


def run_cell(config: EvolutionConfig, data) -> dict[str, Any]:
    """Evolve one genome (``sgb.evolution.evolve``); a flat record with its compression."""
    began = time.perf_counter()
    in_types, hidden_types, out_types = config.cell_types
    sizes = (data.x_train.shape[1], config.hidden, data.num_classes)
    out_types = data.num_classes if out_types is None else out_types
    in_types = sizes[0] if in_types is None else in_types
    record: dict[str, Any] = {
        "hidden_types": hidden_types,
        "stochastic": config.stochastic,
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
    """Evolve every cell of ``profile`` not yet in its results file, writing the file with
    provenance after each."""
    recording = start(PROFILES, profile, out_dir, lambda sweep: f"evolution_{sweep.dataset}")
    sweep = recording.config
    data = load(sweep.dataset, seed=0)
    return train_cells(
        recording.path,
        sweep.cells(),
        list(recording.earlier().get("records", [])),
        (_key, lambda r: (r["hidden_types"], r["stochastic"], r["seed"])),
        lambda cell: run_cell(cell, data),
        lambda records: _write(recording, records),
        f"evolution {sweep.dataset}",
        progress,
    )


def _write(recording: Recording, records: list[dict]) -> Path:
    results = {"dataset": recording.config.dataset, "records": records}
    return recording.write(results, recording.config.seeds, parts=records)


PROFILES: dict[str, EvolutionSweep] = {
    "smoke": EvolutionSweep(
        "digits",
        EvolutionConfig(hidden=16, candidates=16, individuals=4, generations=20, batch_size=128),
        hidden_types=(2,),
        seeds=(0,),
    ),
    "cpu": EvolutionSweep(
        "digits", EvolutionConfig(generations=2000), hidden_types=(2, 8), seeds=(0, 1, 2, 3, 4)
    ),
    "paper": EvolutionSweep(
        "fashion-mnist",
        EvolutionConfig(hidden=64, generations=10_000),
        hidden_types=(2, 8),
        seeds=(0, 1, 2, 3, 4),
    ),
}


def evolution_rows(results: "EvolutionResults") -> list[Row]:
    """Evolution without gradients (``sgb.experiments.evolution``): per number of hidden
    types, the stochastic genome's individuals (their mean test accuracy) against the
    deterministic genome's network, paired by seed (both start from the same means)."""
    records = results.records
    rows = []
    for k in sorted({r.hidden_types for r in records}):
        by_seed = {
            stochastic: {
                r.seed: r for r in records if r.hidden_types == k and r.stochastic is stochastic
            }
            for stochastic in (True, False)
        }
        seeds = sorted(set(by_seed[True]) & set(by_seed[False]))
        if len(seeds) < 2:
            continue
        stochastic = [100 * np.mean(by_seed[True][s].individuals) for s in seeds]
        deterministic = [100 * by_seed[False][s].mean_network for s in seeds]
        first = by_seed[True][seeds[0]]
        rows.append(
            judge(
                "ch6.evolution_stochastic_helps",
                f"{results.dataset}, {k} hidden types ({first.compression:.0f}x)",
                stats.paired(stochastic, deterministic),
                f"{len(first.mean_fitness)} generations, {len(seeds)} seeds",
            )
        )
    return rows


def evolution(payload: "Evolution | None") -> dict[str, str]:
    """Evolution without gradients (``evolution_digits_cpu.json``): the design
    (``evo_design``), per number of hidden types k the two genomes' test accuracies
    (``evo_k{k}_stochastic``, ``evo_k{k}_deterministic``: mean +- SEM over seeds, %), the
    evolved spreads (``evo_sigma``) and the rows of ``evolution_rows``
    (``evo_k{k}_*``); ``NOT_RUN`` for all without the file. Names for k = 2 and 8."""
    texts = {"evo_design": NOT_RUN, "evo_sigma": NOT_RUN}
    for k in (2, 8):
        texts |= {f"evo_k{k}_{g}": NOT_RUN for g in ("stochastic", "deterministic")}
        texts |= row_texts(f"evo_k{k}", None)
    if payload is None:
        return texts
    records = payload.results.records
    candidates = payload.provenance.config.base.candidates
    texts["evo_design"] = (
        f"{len(records[0].mean_fitness)} generations of {candidates} candidate genomes, "
        f"{len({r.seed for r in records})} seeds"
    )
    sigma = [r.sigma_mean for r in records if r.stochastic]
    texts["evo_sigma"] = f"{min(sigma):.2f} to {max(sigma):.2f}"
    for k in (2, 8):
        for stochastic, name in ((True, "stochastic"), (False, "deterministic")):
            values = np.array(
                [
                    100 * np.mean(r.individuals)
                    for r in records
                    if r.hidden_types == k and r.stochastic is stochastic
                ]
            )
            if values.size > 1:
                sem = values.std(ddof=1) / math.sqrt(values.size)
                texts[f"evo_k{k}_{name}"] = f"{values.mean():.1f} ± {sem:.1f} %"
    card = claims.by_key(evolution_rows(payload.results))
    for k in (2, 8):
        texts |= row_texts(
            f"evo_k{k}", row_of(card, "ch6.evolution_stochastic_helps", f" {k} hidden")
        )
    return texts


def evidence(records: Records) -> list[Row]:
    """The stochastic genome against the deterministic one (``evolution_rows``)."""
    payload = records.get("evolution")
    return [] if payload is None else evolution_rows(payload.results)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 6 glues of evolution (``evolution``)."""
    return evolution(records("evolution"))


def evolution_table(payload: "Evolution") -> pd.DataFrame:
    """Evolution without gradients (``sgb.experiments.evolution``), one row per cell:
    hidden types, compression (ours), genome, seed, the last generation's mean fitness,
    the test accuracy (%) of the evolved genome's individuals (their mean and SD, in
    points) and of its mean network, the evolved spreads' mean sigma and the wall time."""
    return pd.DataFrame(
        {
            "hidden types": r.hidden_types,
            "compression": r.compression,
            "genome": "stochastic" if r.stochastic else "deterministic",
            "seed": r.seed,
            "last fitness": r.mean_fitness[-1],
            "individuals (% accuracy)": 100 * float(np.mean(r.individuals)),
            "SD of individuals (points)": 100 * float(np.std(r.individuals, ddof=1)),
            "mean network (% accuracy)": 100 * r.mean_network,
            "sigma": r.sigma_mean,
            "wall time (s)": r.wall_time_s,
        }
        for r in payload.results.records
    )


class EvolutionRecord(Record):
    hidden_types: Count
    stochastic: bool
    seed: Seed
    compression: Compression
    mean_fitness: List[Accuracy]
    individuals: List[Accuracy]
    mean_network: Accuracy
    sigma_mean: NonNegative
    wall_time_s: Seconds


class EvolutionResults(Record):
    dataset: str
    records: List[EvolutionRecord]


class Candidates(Record):
    candidates: Count


class SweepConfig(Record):
    base: Candidates


class EvolutionProvenance(Provenance):
    config: SweepConfig


class Evolution(ResultsFile):
    provenance: EvolutionProvenance
    results: EvolutionResults
