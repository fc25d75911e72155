"""Figure 2's SGB as the paper and the authors train it, at every ratio of Figure 2.

The authors' supervised SGB (``supervised_learning/MNIST_SGB.py`` in their repository;
``AUTHORS-SETTINGS.md``): Adam at 1e-3, batches of 64, three weight draws per minibatch
(whole individuals, no local reparameterisation), a Gaussian prior of SD 0.1, the KL per
synapse weighted 1/n_train, sigma = softplus(rho) from rho = -7; the paper's table gives
50 epochs. Their "best validation" reload keeps the last epoch's network (a bug of theirs,
``AUTHORS-SETTINGS.md``), so the last epoch's, as here, is what they reported.

Three variants, each at the seven ratios x three seeds of Figure 2's sweep:

- ``authors``: the above; the main setting, being the paper's;
- ``per_pair``: the KL counted once per type pair, rho from -7;
- ``rho_ours``: the KL per synapse, rho from -5 (Figure 2's committed sweep starts there).

Under the KL's pull rho climbs at about Adam's largest step, so where sigma ends depends
on where rho starts and on the number of steps (chapter 2): each record keeps, per layer,
the trained sigma averaged over its synapses (``layers``, ``sgb.moments.layer_statistics``)
beside the accuracies.

A cell is one variant, ratio and seed, trained by ``sgb.supervised_sweep.run_one`` under
a lock (``sgb.runlock``), so several processes share the sweep; each finished cell is
added to the results file at once (under that file's lock).
"""

import dataclasses
from pathlib import Path

from tqdm.auto import tqdm

from sgb import runlock, validation
from sgb.classifiers import dense_sizes
from sgb.data import load
from sgb.priors import GaussianPrior
from sgb.recording import Recording, start
from sgb.supervised import ClassifierConfig
from sgb.supervised_sweep import IMAGE_RATIOS, CompressionSweep, run_one, sweep_cells, sweep_summary

VARIANTS: dict[str, dict] = {
    "authors": {"kl_counting": "synapse", "rho_init": -7.0},
    "per_pair": {"kl_counting": "table", "rho_init": -7.0},
    "rho_ours": {"kl_counting": "synapse", "rho_init": -5.0},
}
AUTHORS_SGB = ClassifierConfig(
    prior=GaussianPrior(0.1),
    kl_counting="synapse",
    kl_scale=1.0,
    rho_init=-7.0,
    num_samples=3,
    learning_rate=1e-3,
    batch_size=64,
    epochs=50,
)


@dataclasses.dataclass(frozen=True)
class FullSGBSweep:
    """The cells: every ``variants`` x ``sweep`` cell (its SGB ratios and seeds) on ``dataset``."""

    dataset: str
    sweep: CompressionSweep
    variants: tuple[str, ...] = tuple(VARIANTS)

    def __post_init__(self) -> None:
        for i, name in enumerate(self.variants):
            validation.choice(f"variants[{i}]", name, tuple(VARIANTS))
        if self.sweep.models != ("sgb",):
            raise ValueError(f"the sweep trains the SGB alone, got models {self.sweep.models}")

    def of(self, variant: str) -> CompressionSweep:
        """The sweep of ``variant``: its SGB's KL counting and rho start."""
        return dataclasses.replace(
            self.sweep, sgb=dataclasses.replace(self.sweep.sgb, **VARIANTS[variant])
        )


def _sgb_sweep(ratios, seeds, hidden, sgb: ClassifierConfig) -> CompressionSweep:
    return CompressionSweep(ratios=ratios, seeds=seeds, hidden=hidden, models=("sgb",), sgb=sgb)


_SMOKE_SGB = dataclasses.replace(AUTHORS_SGB, epochs=1, eval_individuals=3)
PROFILES = {
    "smoke": FullSGBSweep("digits", _sgb_sweep((4.0,), (0,), (64,), _SMOKE_SGB)),
    "cpu": FullSGBSweep("fashion-mnist", _sgb_sweep(IMAGE_RATIOS, (0, 1, 2), (800,), AUTHORS_SGB)),
    "paper": FullSGBSweep(
        "fashion-mnist", _sgb_sweep(IMAGE_RATIOS, (0, 1, 2, 3, 4), (800,), AUTHORS_SGB)
    ),
}


def cell_name(variant: str, setting: int, seed: int) -> str:
    return f"{variant}_k{setting}_s{seed}"


def run(profile: str, out_dir: Path, progress: bool = True) -> Path:
    """Train every cell that no other process holds and no run has finished."""
    recording = start(PROFILES, profile, out_dir, lambda full: f"sgb_full_{full.dataset}")
    full, path = recording.config, recording.path
    data = load(full.dataset, seed=0)
    sweep = full.sweep
    sizes = dense_sizes(data.x_train.shape[1:], sweep.conv_features, sweep.hidden, data.num_classes)
    cells = [(v, cell) for v in full.variants for cell in sweep_cells(full.of(v), sizes)]
    for variant, (kind, setting, seed) in tqdm(
        cells, desc=f"sgb_full {full.dataset}", disable=not progress
    ):
        name = cell_name(variant, setting, seed)
        with runlock.claim(path.with_name(f"{path.stem}_{name}")) as mine:
            with runlock.exclusive(path):
                done = recording.earlier().get("cells", {})
            if not mine or name in done:
                continue
            record = {"variant": variant, **run_one(kind, setting, seed, data, full.of(variant))}
            with runlock.exclusive(path):
                done = recording.earlier().get("cells", {}) | {name: record}
                _write(recording, sizes, done)
    with runlock.exclusive(path):
        return _write(recording, sizes, recording.earlier().get("cells", {}))


def _write(recording: Recording, sizes: tuple[int, ...], cells: dict) -> Path:
    full, records = recording.config, list(cells.values())
    results = {
        "dataset": full.dataset,
        "sizes": list(sizes),
        "cells": cells,
        "complete": len(cells) == len(full.variants) * len(sweep_cells(full.sweep, sizes)),
        "variants": {
            v: sweep_summary([r for r in records if r["variant"] == v])
            for v in full.variants
            if any(r["variant"] == v for r in records)
        },
    }
    return recording.write(results, full.sweep.seeds, parts=records)
