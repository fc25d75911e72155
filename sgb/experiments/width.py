"""Whether the SGB's lead over the DGB grows with the network, at a fixed genome: the
abstract's "stochasticity confers a greater benefit in large networks", which the paper
draws from Figure 2's high compressions.

At each hidden width of a one-hidden-layer Fashion-MNIST network (Figure 2's is 800), the
SGB as the authors train it (``sgb.supervised_sweep.AUTHORS_SGB``: 50 epochs, rho from -7,
the KL per synapse) with 10 hidden types, 30 input and 10 output types, against the DGB in
the authors' layout at the g-net width whose compression (our count) is nearest the
SGB's, trained 500 rounds with the network of best validation accuracy kept
(``sgb.supervised_sweep.run_one``). The genome stays the same size while the network
grows, so the wider network is the more compressed one.

Each cell (model, width, seed) is trained under a lock (``sgb.cells.train_cells``,
shared), so several processes share the sweep; the results file is written after each.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd

from sgb import stats
from sgb.cells import train_cells
from sgb.claims import Row, judge
from sgb.classifiers import dense_sizes
from sgb.compression import compression
from sgb.data import load, shape_of
from sgb.dgb import DGBConfig
from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.prose import NOT_RUN, Card, row_texts
from sgb.provenance import read_results, results_file
from sgb.queued import Queue, file_run, run_lock
from sgb.recording import start
from sgb.results import Records
from sgb.schemas import Accuracy, Compression, Count, List, Record, ResultsFile, Seed
from sgb.supervised import ClassifierConfig
from sgb.supervised_sweep import AUTHORS_SGB, CompressionSweep, run_one, sweep_cells


@dataclasses.dataclass(frozen=True)
class WidthSweep:
    """The cells: the SGB with ``hidden_types`` and the DGB at the same compression, at
    every hidden width of ``widths`` and seed of ``seeds``, on ``dataset``."""

    dataset: str
    widths: tuple[int, ...]
    hidden_types: int
    seeds: tuple[int, ...]
    sgb: ClassifierConfig = AUTHORS_SGB
    dgb: DGBConfig = DGBConfig(rounds=500, layout="authors")
    in_types: int = 30
    out_types: int = 10

    def sweep(self, width: int, input_shape: tuple[int, ...], classes: int) -> CompressionSweep:
        """The two-model sweep at ``width``: its one ratio the SGB's compression there."""
        sizes = dense_sizes(input_shape, (), (width,), classes)
        ratio = compression("sgb", sizes, self.hidden_types, self.in_types, self.out_types)
        return CompressionSweep(
            ratios=(ratio,),
            seeds=self.seeds,
            hidden=(width,),
            in_types=self.in_types,
            out_types=self.out_types,
            models=("sgb", "dgb"),
            sgb=self.sgb,
            dgb=self.dgb,
        )


PROFILES = {
    "smoke": WidthSweep(
        "digits",
        (16, 64),
        4,
        (0,),
        dataclasses.replace(AUTHORS_SGB, epochs=1, eval_individuals=3),
        DGBConfig(rounds=2, pnet_steps=5, batch_size=32, validation_size=200, layout="authors"),
        in_types=8,
        out_types=10,
    ),
    **{p: WidthSweep("fashion-mnist", (200, 800, 3200), 10, (0, 1, 2)) for p in PROFILE_NAMES[1:]},
}


def _cells(config: WidthSweep, input_shape: tuple[int, ...], classes: int) -> list[tuple]:
    """Every (width, (model, setting, seed)), the narrowest width first."""
    return [
        (w, cell)
        for w in config.widths
        for cell in sweep_cells(
            config.sweep(w, input_shape, classes), _sizes(w, input_shape, classes)
        )
    ]


def _sizes(width: int, input_shape: tuple[int, ...], classes: int) -> tuple[int, ...]:
    return dense_sizes(input_shape, (), (width,), classes)


def _key(width: int, model: str, seed: int) -> str:
    return f"{model}_w{width}_s{seed}"


def _record_key(record: dict) -> str:
    return _key(record["width"], record["model"], record["seed"])


def run(profile: str, out_dir: Path, progress: bool = True) -> Path:
    """Train every cell that no other process holds and no run has finished."""
    recording = start(PROFILES, profile, out_dir, lambda c: f"width_{c.dataset}")
    config, path = recording.config, recording.path
    data = load(config.dataset, seed=0)
    shape, classes = data.x_train.shape[1:], data.num_classes

    def held() -> list[dict]:
        return list(recording.earlier().get("cells", []))

    def train(item: tuple) -> dict:
        width, (model, setting, seed) = item
        sweep = config.sweep(width, shape, classes)
        return {"width": width, **run_one(model, setting, seed, data, sweep)}

    def write(records: list[dict]) -> Path:
        order = sorted(records, key=lambda r: (r["width"], r["model"], r["seed"]))
        results = {"dataset": config.dataset, "cells": order}
        return recording.write(results, config.seeds, parts=order)

    return train_cells(
        path,
        _cells(config, shape, classes),
        held(),
        (lambda item: _key(item[0], item[1][0], item[1][2]), _record_key),
        train,
        write,
        path.stem,
        progress,
        shared=(
            lambda item: run_lock(path, _key(item[0], item[1][0], item[1][2])),
            held,
        ),
    )


def queued(profile: str, results_dir: Path) -> Queue:
    """The cells of ``profile`` under ``results_dir``, in the order they train (each one
    chunk: a cell is not resumable), for the background queue (``sgb.grid``)."""
    config = PROFILES[check_profile(profile)]
    path = results_file(results_dir, f"width_{config.dataset}", profile)
    done = {
        _record_key(r): r for r in (read_results(path)["results"]["cells"] if path.exists() else [])
    }
    runs = []
    for width, (model, _, seed) in _cells(config, *shape_of(config.dataset)):
        key = _key(width, model, seed)
        label = f"{model.upper()} width {width} seed {seed}"
        runs.append(file_run(label, path, key, done.get(key)))
    return Queue(path, tuple(runs))


def gaps(results: "WidthResults") -> dict[int, np.ndarray]:
    """Per width with both models at 2 seeds or more: SGB minus DGB test accuracy
    (points), paired by seed (over the seeds both have)."""
    out = {}
    for width in sorted({c.width for c in results.cells}):
        of = {
            m: {c.seed: c.accuracy for c in results.cells if c.width == width and c.model == m}
            for m in ("sgb", "dgb")
        }
        seeds = sorted(set(of["sgb"]) & set(of["dgb"]))
        if len(seeds) >= 2:
            out[width] = np.array([100 * (of["sgb"][s] - of["dgb"][s]) for s in seeds])
    return out


def width_rows(results: "WidthResults", dataset: str) -> list[Row]:
    """The claim's row: the slope of the SGB's lead (points, paired by seed) on log2 of
    the hidden width, over the widths with 2 seeds or more; none before 2 widths have."""
    by_width = gaps(results)
    if len(by_width) < 2:
        return []
    x = np.concatenate([np.full(g.size, np.log2(w)) for w, g in by_width.items()])
    y = np.concatenate(list(by_width.values()))
    widths = ", ".join(f"{w:,}" for w in by_width)
    seeds = min(g.size for g in by_width.values())
    return [
        judge(
            "abstract.larger_networks",
            f"{dataset}, hidden widths {widths}, 10 hidden types; the authors' SGB against "
            "their DGB at the same compression",
            stats.slope(x, y),
            f"{seeds} seeds a width; SGB 50 epochs, DGB 500 rounds",
            amount=50,
        )
    ]


def width_table(results: "WidthResults") -> pd.DataFrame:
    """Per width and model: the compression (both counts), its setting (hidden types or
    g-net width), the mean test accuracy (%) over its seeds and their number."""
    frame = pd.DataFrame(
        {
            "width": c.width,
            "model": c.model,
            "setting": c.setting,
            "compression (ours)": c.compression,
            "compression (authors')": c.compression_authors,
            "accuracy %": 100 * c.accuracy,
        }
        for c in results.cells
    )
    return frame.groupby(["width", "model", "setting"]).agg(
        **{
            "compression (ours)": ("compression (ours)", "mean"),
            "compression (authors')": ("compression (authors')", "mean"),
            "accuracy %": ("accuracy %", "mean"),
            "seeds": ("accuracy %", "size"),
        }
    )


BOOK_DATASET = "Fashion-MNIST"


def evidence(records: Records) -> list[Row]:
    """The width row (``width_rows``); none before the file is run."""
    payload = records.get("width")
    return [] if payload is None else width_rows(payload.results, BOOK_DATASET)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 4 glues: the width row (``width_*``) and each width's lead
    (``width_gaps``: mean and SEM over seeds, points)."""
    rows = card.get("abstract.larger_networks", [])
    payload = records.get("width")
    by_width = {} if payload is None else gaps(payload.results)
    leads = "; ".join(
        f"{w:,} wide: {g.mean():+.1f} ± {stats.sem(g):.1f}" for w, g in by_width.items()
    )
    return row_texts("width", rows[0] if rows else None) | {"width_gaps": leads or NOT_RUN}


class WidthCell(Record):
    width: Count
    model: str
    setting: Count
    seed: Seed
    accuracy: Accuracy
    compression: Compression
    compression_authors: Compression


class WidthResults(Record):
    cells: List[WidthCell]


class Width(ResultsFile):
    results: WidthResults
