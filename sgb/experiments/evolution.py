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
import time
from pathlib import Path
from typing import Any

from sgb import validation
from sgb.cells import train_cells
from sgb.compression import compression
from sgb.data import DATASETS, load
from sgb.evolution import EvolutionConfig, evolve
from sgb.provenance import git_commit
from sgb.recording import Recording, start


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
