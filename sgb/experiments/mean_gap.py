"""Why the SGB's individuals beat their mean network on Fashion-MNIST: the moment-matched
network.

Figure 2's ``cpu`` sweep on Fashion-MNIST (KL per synapse) ends with sampled individuals
26-30 points above their mean network (every weight at its mean). This experiment trains
the same SGB cells as that sweep, with its config and its training call, at a few
compression ratios and seeds, and evaluates each on the test set three ways:

* the individuals (as many as the sweep samples, drawn with the same keys),
* the mean network,
* the moment-matched network (``sgb.moments``): every pre-activation's mean and variance
  carried through the Gaussian weights, ReLU moments in closed form, the argmax of the
  output mean. For one hidden layer its output mean is the exact expectation of the
  logits over individuals.

Each record also holds, per layer, the per-synapse mean |mu|, sigma and rho at the start
and the end of training, and how far rho moved as a fraction of ``steps x learning rate``
(about the farthest Adam can move one parameter), and the mean hidden activation of the
individuals (its moment) and of the mean network. A second setting trains the cells of
``other_rho_ratios`` from ``other_rho_init`` (the authors' rho, -7) instead of the sweep's,
to see whether the final spread is set by where rho starts.

``run`` writes ``mean_gap_<dataset>_<profile>.json`` after every cell, atomically, with
provenance; a rerun with the same config skips the cells already there.
"""

import dataclasses
import math
import time
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd

from sgb import moments, validation
from sgb.cells import train_cells
from sgb.classifiers import dense_sizes
from sgb.compression import compression, setting_for_ratio
from sgb.data import Dataset, load
from sgb.individuals import init_params
from sgb.prose import Card, mean_sem
from sgb.provenance import git_commit
from sgb.recording import Recording, start
from sgb.results import Records
from sgb.schemas import (
    Accuracy,
    Compression,
    Count,
    Finite,
    List,
    NonNegative,
    Record,
    ResultsFile,
    Seed,
)
from sgb.stats import sem
from sgb.supervised import make_model, train_and_evaluate
from sgb.supervised_sweep import SWEEPS, CompressionSweep, cell_config

METRICS = ("accuracy", "mean_network", "moment_network")


@dataclasses.dataclass(frozen=True)
class MeanGapConfig:
    """SGB cells of Figure 2's ``sweep`` on ``dataset``: the hidden types nearest each of
    ``ratios`` (our convention, as the sweep chooses them) trained from the sweep's
    ``rho_init``, and those nearest ``other_rho_ratios`` trained from ``other_rho_init``,
    each for every seed of ``seeds``."""

    dataset: str = "fashion-mnist"
    sweep: CompressionSweep = SWEEPS["cpu"]["fashion-mnist"]["sweep"]
    ratios: tuple[float, ...] = (10.0, 400.0)
    other_rho_init: float = -7.0
    other_rho_ratios: tuple[float, ...] = (10.0,)
    seeds: tuple[int, ...] = (0, 1, 2)

    def __post_init__(self) -> None:
        validation.instance("sweep", self.sweep, CompressionSweep)
        if self.sweep.conv_features:
            raise ValueError("the moment-matched network covers SGB MLPs, not conv trunks")
        if not self.ratios:
            raise ValueError("ratios must not be empty")
        for name in ("ratios", "other_rho_ratios"):
            for i, ratio in enumerate(getattr(self, name)):
                validation.positive(f"{name}[{i}]", ratio)
        validation.real("other_rho_init", self.other_rho_init)
        validation.integers("seeds", self.seeds, minimum=0)


def cells(config: MeanGapConfig, sizes: tuple[int, ...]) -> list[tuple[int, float, int]]:
    """Every (hidden types, rho_init, seed) of ``config``, seed by seed."""
    sweep = config.sweep

    def settings(ratios: tuple[float, ...]) -> list[int]:
        return sorted(
            {setting_for_ratio("sgb", sizes, r, sweep.in_types, sweep.out_types) for r in ratios}
        )

    pairs = [(s, float(sweep.sgb.rho_init)) for s in settings(config.ratios)]
    pairs += [(s, float(config.other_rho_init)) for s in settings(config.other_rho_ratios)]
    return [(s, rho, seed) for seed in config.seeds for s, rho in pairs]


def _layer_record(start: dict, end: dict, max_travel: float) -> dict[str, Any]:
    """One layer's statistics at the start and the end of training, and rho's travel as a
    fraction of ``max_travel`` (steps x learning rate)."""
    keys = ("mean_abs_mu", "mean_sigma", "mean_rho")
    return {
        "layer": end["layer"],
        "shape": end["shape"],
        "types": end["types"],
        "start": {k: start[k] for k in keys},
        "end": {k: end[k] for k in keys},
        "rho_travel_fraction": (end["mean_rho"] - start["mean_rho"]) / max_travel,
    }


def _per_synapse(layers: list[dict], when: str, key: str) -> float:
    """``key`` at ``when`` averaged over every synapse of the network."""
    weights = [math.prod(layer["shape"]) for layer in layers]
    values = [layer[when][key] for layer in layers]
    return float(np.average(values, weights=weights))


def _hidden_activations(params: Any, x: np.ndarray) -> list[dict[str, float]]:
    """Per hidden layer, the mean over test inputs and units of the individuals' expected
    activation E[relu(a)] (its moment) and of the mean network's activation."""
    layers = moments.mlp_layers(params)
    noisy = moments.propagate(layers, x)
    plain = moments.propagate(moments.without_noise(layers), x)
    return [
        {
            "individuals": float(moments.relu_moments(*a).mean.mean()),
            "mean_network": float(jnp.maximum(b.mean, 0.0).mean()),
        }
        for a, b in zip(noisy[:-1], plain[:-1], strict=True)
    ]


def run_cell(
    setting: int, rho_init: float, seed: int, data: Dataset, sweep: CompressionSweep
) -> dict:
    """Train one SGB cell as Figure 2's sweep does (``train_and_evaluate``) and evaluate
    its individuals, mean network and moment-matched network; a flat record."""
    start_time = time.perf_counter()
    config = cell_config(sweep, setting, seed, rho_init)
    in_features = int(np.prod(data.x_train.shape[1:]))
    sizes = dense_sizes(data.x_train.shape[1:], (), sweep.hidden, data.num_classes)
    # the params training starts from (sgb.supervised.train_classifier draws them so)
    initial = init_params(
        make_model(config, data.num_classes, data.x_train.shape[1:]),
        jax.random.key(seed),
        data.x_train[:1],
    )
    out = train_and_evaluate(config, data, progress=False)
    params = out["params"]
    steps = config.epochs * max(1, len(data.x_train) // config.batch_size)
    max_travel = steps * config.learning_rate
    layers = [
        _layer_record(a, b, max_travel)
        for a, b in zip(
            moments.layer_statistics(initial, in_features),
            moments.layer_statistics(params, in_features),
            strict=True,
        )
    ]
    individuals = np.asarray(out["accuracy"]["individuals"])
    record: dict[str, Any] = {
        "model": "sgb",
        "setting": setting,
        "rho_init": float(rho_init),
        "seed": seed,
        "accuracy": float(individuals.mean()),
        "individual_sd": float(individuals.std(ddof=1)) if individuals.size > 1 else 0.0,
        "individuals": individuals.tolist(),
        "mean_network": out["accuracy"]["mean_network"],
        "moment_network": moments.moment_accuracy(params, data.x_test, data.y_test),
        "population_average": out["accuracy"]["population_average"],
        "sigma_start": _per_synapse(layers, "start", "mean_sigma"),
        "sigma_end": _per_synapse(layers, "end", "mean_sigma"),
        "abs_mu_end": _per_synapse(layers, "end", "mean_abs_mu"),
        "layers": layers,
        "hidden_activation": _hidden_activations(params, data.x_test),
        "steps": steps,
        "learning_rate": config.learning_rate,
        "final_kl": out["history"][-1]["kl"],
        "final_loss": out["history"][-1]["loss"],
    }
    for convention, key in (("ours", "compression"), ("authors", "compression_authors")):
        record[key] = compression(
            "sgb", sizes, setting, sweep.in_types, sweep.out_types, convention
        )
    record["git_commit"] = git_commit()
    record["wall_time_s"] = round(time.perf_counter() - start_time, 2)
    return record


def summarise(records: list[dict]) -> list[dict[str, Any]]:
    """Per (setting, rho_init), by compression: mean and SEM over seeds (NaN with one seed)
    of the three accuracies and of the final sigma, the gap individuals - mean network and
    the share of it the moment-matched network recovers,
    (moment - mean network) / (individuals - mean network), averaged over seeds."""
    rows = []
    for setting, rho in sorted({(r["setting"], r["rho_init"]) for r in records}):
        group = [r for r in records if r["setting"] == setting and r["rho_init"] == rho]
        row: dict[str, Any] = {
            "setting": setting,
            "rho_init": rho,
            "compression": group[0]["compression"],
            "compression_authors": group[0]["compression_authors"],
            "n": len(group),
        }
        derived = {
            "sigma_end": [r["sigma_end"] for r in group],
            "gap": [r["accuracy"] - r["mean_network"] for r in group],
            "moment_recovery": [
                (r["moment_network"] - r["mean_network"]) / (r["accuracy"] - r["mean_network"])
                if r["accuracy"] != r["mean_network"]
                else math.nan
                for r in group
            ],
        }
        for name, values in {**{m: [r[m] for r in group] for m in METRICS}, **derived}.items():
            values = np.asarray(values, dtype=float)
            row[name] = float(values.mean())
            row[f"{name}_sem"] = float(sem(values)) if values.size > 1 else math.nan
        rows.append(row)
    return sorted(rows, key=lambda row: (row["compression"], -row["rho_init"]))


PROFILES: dict[str, MeanGapConfig] = {
    "smoke": MeanGapConfig(
        dataset="digits",
        sweep=SWEEPS["smoke"]["digits"]["sweep"],
        ratios=(4.0, 30.0),
        other_rho_ratios=(4.0,),
        seeds=(0,),
    ),
    "cpu": MeanGapConfig(),
    "paper": MeanGapConfig(sweep=SWEEPS["paper"]["fashion-mnist"]["sweep"], seeds=(0, 1, 2, 3, 4)),
}


def run(profile: str, out_dir: Path, progress: bool = True) -> Path:
    """Train and evaluate every cell of ``profile`` not yet in its results file, writing
    the file with provenance after each."""
    recording = start(PROFILES, profile, out_dir, lambda config: f"mean_gap_{config.dataset}")
    config = recording.config
    data = load(config.dataset, seed=0)
    sizes = dense_sizes(data.x_train.shape[1:], (), config.sweep.hidden, data.num_classes)
    return train_cells(
        recording.path,
        cells(config, sizes),
        list(recording.earlier().get("records", [])),
        (lambda cell: cell, lambda r: (r["setting"], r["rho_init"], r["seed"])),
        lambda cell: run_cell(*cell, data, config.sweep),
        lambda records: _write(recording, sizes, records),
        "mean gap",
        progress,
    )


def _write(recording: Recording, sizes: tuple[int, ...], records: list[dict]) -> Path:
    results = {
        "dataset": recording.config.dataset,
        "sizes": list(sizes),
        "records": records,
        "summary": summarise(records) if records else [],
    }
    return recording.write(results, recording.config.seeds, parts=records)


def mean_gap(results: "MeanGapResults") -> dict[str, str]:
    """The moment-matched network (``mean_gap_fashion-mnist_cpu.json``'s results): at 10x
    and 400x from rho -5 and at 10x from rho -7 (``gap10``, ``gap400``, ``gap10_rho7``),
    each network's accuracy (% +- SEM), the recovery and the trained sigma; per rho start,
    the hidden layer's rho travel and end (``gap_travel_5``, ``gap_rho_end_7``, ...), and
    the training steps (``gap_steps``)."""
    cells = {(r.setting, r.rho_init): r for r in results.summary}
    texts = {}
    for name, cell in (("gap10", (785, -5.0)), ("gap400", (10, -5.0)), ("gap10_rho7", (785, -7.0))):
        row = cells[cell]
        for key in ("accuracy", "mean_network", "moment_network"):
            mean, sem = getattr(row, key), getattr(row, f"{key}_sem")
            texts[f"{name}_{key}"] = f"{100 * mean:.1f} ± {100 * sem:.1f} %"
        texts[f"{name}_recovery"] = f"{row.moment_recovery:.2f}"
        texts[f"{name}_sigma"] = f"{row.sigma_end:.3f}"
    for r in results.records:
        if r.setting == 785 and r.seed == 0:
            layer = r.layers[0]
            texts[f"gap_travel_{-r.rho_init:g}"] = f"{layer.rho_travel_fraction:.2f}"
            texts[f"gap_rho_end_{-r.rho_init:g}"] = f"{layer.end.mean_rho:.2f}"
    texts["gap_steps"] = str(results.records[0].steps)
    return texts


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 4 glues of the moment-matched mean network (``mean_gap``)."""
    return mean_gap(records("mean_gap").results)


def mean_gap_table(results: "MeanGapResults") -> pd.DataFrame:
    """The mean network's gap (``sgb.experiments.mean_gap``), one row per cell (hidden
    types, rho start): compression both ways, seeds, and means ± SEM over seeds of the test
    accuracy (%) of the individuals, their mean network and the moment-matched network, the
    gap individuals minus mean network (points), the trained sigma and the moment-matched
    network's recovery of that gap (a ratio)."""

    def cell(mean: float, sem: float | None, scale: float, decimals: int) -> str:
        return mean_sem(mean, math.nan if sem is None else sem, scale, decimals)

    return pd.DataFrame(
        {
            "hidden types": s.setting,
            "rho start": s.rho_init,
            "compression (ours)": s.compression,
            "compression (authors')": s.compression_authors,
            "seeds": s.n,
            "individuals %": cell(s.accuracy, s.accuracy_sem, 100.0, 1),
            "mean network %": cell(s.mean_network, s.mean_network_sem, 100.0, 1),
            "moment-matched %": cell(s.moment_network, s.moment_network_sem, 100.0, 1),
            "gap (points)": cell(s.gap, s.gap_sem, 100.0, 1),
            "trained sigma": cell(s.sigma_end, s.sigma_end_sem, 1.0, 4),
            "recovery": cell(s.moment_recovery, s.moment_recovery_sem, 1.0, 2),
        }
        for s in results.summary
    )


class MeanRho(Record):
    mean_rho: Finite


class GapLayer(Record):
    rho_travel_fraction: Finite
    end: MeanRho


class MeanGapRecord(Record):
    setting: Count
    seed: Seed
    rho_init: Finite
    steps: Count
    layers: List[GapLayer]


class MeanGapSummary(Record):
    """Per setting: the individuals' accuracy and the two networks', the gap, the trained
    sigma and the recovery, each with its SEM (null with one seed)."""

    setting: Count
    rho_init: Finite
    compression: Compression
    compression_authors: Compression
    n: Count
    moment_recovery: Finite
    sigma_end: NonNegative
    accuracy: Accuracy
    mean_network: Accuracy
    moment_network: Accuracy
    gap: Finite
    accuracy_sem: NonNegative | None
    mean_network_sem: NonNegative | None
    moment_network_sem: NonNegative | None
    gap_sem: NonNegative | None
    sigma_end_sem: NonNegative | None
    moment_recovery_sem: NonNegative | None


class MeanGapResults(Record):
    dataset: str
    records: List[MeanGapRecord]
    summary: List[MeanGapSummary]


class MeanGap(ResultsFile):
    results: MeanGapResults
