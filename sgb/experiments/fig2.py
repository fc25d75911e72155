"""Figure 2: innate test accuracy of DGB and SGB against compression ratio.

``run(profile, out_dir, dataset=...)`` sweeps SGB, DGB and the uncompressed
network over compression ratios and seeds on one dataset and writes
``fig2_<dataset>_<profile>.json`` (``sgb.provenance.results_file``, so a quick check
never overwrites committed results) with provenance.

The run is resumable: the file is rewritten atomically after every finished
(model, setting, seed) cell, and a rerun with the same config skips the cells
already there. ``models`` and ``seeds`` restrict a run to part of the sweep.

Every record carries its compression ratio under both conventions of
``sgb.compression`` ("ours" and "authors"); summaries and crossovers are
computed under each. ``at_chance`` marks a record whose accuracy is no better than
chance (``sgb.supervised.at_chance``; absent from records written before it existed).

KL choice (see the book's chapter 4): on MNIST-like data the KL to a N(0, 0.1^2)
prior is counted per expanded synapse and weighted 1/n_train, the authors'
setting; counting it once per type pair (the genome view) is the ablation. On the
small sets (digits, mnist1d), where that per-synapse KL dominates the loss, per
type pair is the main setting and per synapse the ablation.
"""

from pathlib import Path

from sgb.cells import train_cells
from sgb.classifiers import dense_sizes
from sgb.data import load
from sgb.recording import Recording, start
from sgb.supervised_sweep import SWEEPS, run_one, sweep_cells, sweep_summary

# the registry reads an experiment's profiles here: profile -> dataset -> sweep and ablation
PROFILES = SWEEPS


def run(
    profile: str,
    out_dir: Path,
    dataset: str = "digits",
    progress: bool = True,
    models: tuple[str, ...] | None = None,
    seeds: tuple[int, ...] | None = None,
) -> Path:
    """Run the sweep of ``profile`` on ``dataset`` (optionally only some ``models`` and
    ``seeds``), skipping finished cells, and write its results with provenance."""
    recording = start(PROFILES, profile, out_dir, f"fig2_{dataset}", choice=dataset)
    sweep, ablation = recording.config["sweep"], recording.config["ablation"]
    earlier = recording.earlier()
    data = load(dataset, seed=0)
    sizes = dense_sizes(data.x_train.shape[1:], sweep.conv_features, sweep.hidden, data.num_classes)
    groups = {"records": sweep, "ablation_records": ablation}
    cells = [
        (group, cell)
        for group, part in groups.items()
        if part is not None
        for cell in sweep_cells(part, sizes)
        if (models is None or cell[0] in models) and (seeds is None or cell[2] in seeds)
    ]

    def train(item: tuple[str, tuple[str, int, int]]) -> tuple[str, dict]:
        group, (kind, setting, seed) = item
        return group, run_one(kind, setting, seed, data, groups[group])

    return train_cells(
        recording.path,
        cells,
        [(group, r) for group in groups for r in earlier.get(group, [])],
        (lambda item: item, lambda kept: (kept[0], _cell(kept[1]))),
        train,
        lambda kept: _write(recording, dataset, sizes, kept),
        f"fig2 {dataset}",
        progress,
    )


def _cell(record: dict) -> tuple[str, int, int]:
    return record["model"], record["setting"], record["seed"]


def _write(
    recording: Recording, dataset: str, sizes: tuple[int, ...], kept: list[tuple[str, dict]]
) -> Path:
    """Write the records ``kept`` (group, record), each group in its list."""
    done = {g: [r for h, r in kept if h == g] for g in ("records", "ablation_records")}
    records = done["records"]
    results = {"dataset": dataset, "sizes": list(sizes), **done, **sweep_summary(records)}
    seeds = recording.config["sweep"].seeds
    return recording.write(results, seeds, parts=records + done["ablation_records"])
