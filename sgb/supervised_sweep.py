"""Figure 2's sweep: innate accuracy of the SGB, the DGB and the uncompressed network
against compression, one (model, setting, seed) cell at a time (``run_one``), its
summaries and SGB/DGB crossovers under both conventions of ``sgb.compression``, and the
sweeps themselves at each profile and dataset (``SWEEPS``), which ``sgb.experiments.fig2``
runs and the experiments beside it reuse.
"""

import dataclasses
import math
from typing import Any

import numpy as np

from sgb import moments, validation
from sgb.classifiers import dense_sizes
from sgb.compression import CONVENTIONS, MODEL_KINDS, compression, setting_for_ratio
from sgb.data import Dataset
from sgb.dgb import DGBConfig
from sgb.priors import GaussianPrior
from sgb.provenance import git_commit
from sgb.schemas import Accuracy, Compression, Finite, NonNegative, Record, Seed
from sgb.stats import crossings, sem
from sgb.supervised import ClassifierConfig, DenseConfig, train_and_evaluate
from sgb.timing import timed

_RATIO_KEYS = {"ours": "compression", "authors": "compression_authors"}


@dataclasses.dataclass(frozen=True)
class CompressionSweep:
    """Innate accuracy against compression for SGB, DGB and the uncompressed network.

    The SGB's input and output layers have ``in_types`` and ``out_types``
    cell types; every hidden layer gets the number of types (SGB) or the g-net
    width (DGB) whose compression (our convention) is nearest each of ``ratios``.
    ``sgb``, ``dgb`` and ``dense`` are training templates; their ``hidden``,
    ``conv_features``, ``cell_types``/``gnet_width`` and ``seed`` are set here.
    """

    ratios: tuple[float, ...] = (10.0, 100.0)
    seeds: tuple[int, ...] = (0,)
    hidden: tuple[int, ...] = (800,)
    conv_features: tuple[int, ...] = ()
    in_types: int = 30
    out_types: int = 10
    models: tuple[str, ...] = MODEL_KINDS
    sgb: ClassifierConfig = ClassifierConfig()
    dgb: DGBConfig = DGBConfig()
    dense: DenseConfig = DenseConfig()

    def __post_init__(self) -> None:
        if not self.ratios:
            raise ValueError("ratios must not be empty")
        for i, ratio in enumerate(self.ratios):
            validation.positive(f"ratios[{i}]", ratio)
        validation.integers("seeds", self.seeds, minimum=0)
        validation.integers("hidden", self.hidden)
        validation.integer("in_types", self.in_types)
        validation.integer("out_types", self.out_types)
        for i, kind in enumerate(self.models):
            validation.choice(f"models[{i}]", kind, MODEL_KINDS)
        validation.instance("sgb", self.sgb, ClassifierConfig)
        validation.instance("dgb", self.dgb, DGBConfig)
        validation.instance("dense", self.dense, DenseConfig)


def sweep_cells(sweep: CompressionSweep, sizes: tuple[int, ...]) -> list[tuple[str, int, int]]:
    """Every (model, setting, seed) of a sweep; the uncompressed network has setting 0."""
    cells = []
    for kind in sweep.models:
        if kind == "dense":
            settings = [0]
        else:
            layout = sweep.dgb.layout
            settings = sorted(
                {
                    setting_for_ratio(
                        kind, sizes, r, sweep.in_types, sweep.out_types, layout=layout
                    )
                    for r in sweep.ratios
                }
            )
        cells += [(kind, s, seed) for seed in sweep.seeds for s in settings]
    return cells


def run_one(kind: str, setting: int, seed: int, data: Dataset, sweep: CompressionSweep) -> dict:
    """Train one model and evaluate it innately; a flat record of the sweep, with its
    wall and CPU time."""
    with timed() as spent:
        record = _trained(kind, setting, seed, data, sweep)
    return record | spent


def _trained(kind: str, setting: int, seed: int, data: Dataset, sweep: CompressionSweep) -> dict:
    shape = {"hidden": sweep.hidden, "conv_features": sweep.conv_features, "seed": seed}
    sizes = dense_sizes(data.x_train.shape[1:], sweep.conv_features, sweep.hidden, data.num_classes)
    record: dict[str, Any] = {"model": kind, "setting": setting, "seed": seed}
    if kind == "sgb":
        types = (sweep.in_types, *([setting] * len(sweep.hidden)), sweep.out_types)
        config = dataclasses.replace(sweep.sgb, cell_types=types, **shape)
    elif kind == "dgb":
        config = dataclasses.replace(sweep.dgb, gnet_width=setting, **shape)
    else:
        config = dataclasses.replace(sweep.dense, **shape)
    out = train_and_evaluate(config, data, progress=False)
    if kind == "sgb":
        individuals = np.asarray(out["accuracy"]["individuals"])
        record |= {
            "accuracy": float(individuals.mean()),
            "individual_sd": float(individuals.std(ddof=1)) if individuals.size > 1 else 0.0,
            "individuals": individuals.tolist(),
            "mean_network": out["accuracy"]["mean_network"],
            "population_average": out["accuracy"]["population_average"],
            "final_kl": out["history"][-1]["kl"],
        }
        if not sweep.conv_features:  # where the spreads ended, per layer (per synapse)
            record["layers"] = moments.layer_statistics(out["params"], sizes[0])
    else:
        record["accuracy"] = out["accuracy"]
    if kind == "dgb":
        record |= {"validation_accuracy": out["validation_accuracy"], "fit_mse": out["fit_mse"]}
        record["layout"] = sweep.dgb.layout
    record["at_chance"] = out["at_chance"]
    record["final_loss"] = out["history"][-1]["loss"]
    for convention, key in _RATIO_KEYS.items():
        record[key] = compression(
            kind, sizes, setting, sweep.in_types, sweep.out_types, convention, sweep.dgb.layout
        )
    record["git_commit"] = git_commit()
    return record


def summarise_compression(
    records: list[dict], metric: str = "accuracy", convention: str = "ours"
) -> dict[str, dict[str, list]]:
    """Per model, sorted by compression under ``convention``: setting, compression, mean and
    SEM of ``metric`` over seeds (SEM is NaN with one seed) and the number of seeds."""
    key = _RATIO_KEYS[convention]
    summary: dict[str, dict[str, list]] = {}
    for kind in sorted({r["model"] for r in records}):
        rows = [r for r in records if r["model"] == kind and r.get(metric) is not None]
        table: dict[str, list] = {k: [] for k in ("setting", "compression", "mean", "sem", "n")}
        for setting in sorted({r["setting"] for r in rows}):
            values = np.array([r[metric] for r in rows if r["setting"] == setting])
            table["setting"].append(setting)
            table["compression"].append(next(r[key] for r in rows if r["setting"] == setting))
            table["mean"].append(float(values.mean()))
            table["sem"].append(float(sem(values)) if values.size > 1 else math.nan)
            table["n"].append(int(values.size))
        order = np.argsort(table["compression"])
        summary[kind] = {k: [v[i] for i in order] for k, v in table.items()}
    return summary


def crossovers(summary: dict[str, dict[str, list]], a: str = "sgb", b: str = "dgb") -> list[float]:
    """Compression ratios where mean accuracy of ``a`` minus ``b`` changes sign
    (``sgb.stats.crossings``: both curves interpolated in log(compression))."""
    return crossings(
        summary[a]["compression"], summary[a]["mean"], summary[b]["compression"], summary[b]["mean"]
    )


def sweep_summary(records: list[dict]) -> dict[str, Any]:
    """Summaries, the SGB mean network's summary and SGB/DGB crossovers, per convention."""
    out: dict[str, Any] = {}
    for convention in CONVENTIONS:
        if not all(_RATIO_KEYS[convention] in r for r in records):
            continue
        summary = summarise_compression(records, convention=convention)
        sgb_records = [r for r in records if r["model"] == "sgb"]
        out[convention] = {
            "summary": summary,
            "summary_mean_network": summarise_compression(sgb_records, "mean_network", convention),
            "crossovers": crossovers(summary) if _comparable(summary) else [],
        }
    return out


def _comparable(summary: dict[str, dict[str, list]], a: str = "sgb", b: str = "dgb") -> bool:
    """Whether curves ``a`` and ``b`` of ``summary`` span a common range of compression,
    each with two points at least, where ``crossovers`` can look for a crossing (a smoke
    sweep has one point a curve)."""
    if not {a, b} <= set(summary):
        return False
    xa, xb = summary[a]["compression"], summary[b]["compression"]
    return len(xa) > 1 and len(xb) > 1 and max(xa[0], xb[0]) < min(xa[-1], xb[-1])


# ----------------------------------------------------------------------------- profiles

# The authors' supervised SGB (``supervised_learning/MNIST_SGB.py``; AUTHORS-SETTINGS.md):
# Adam at 1e-3, batches of 64, three whole-individual draws per minibatch, a Gaussian prior
# of SD 0.1, the KL per synapse weighted 1/n_train, rho from -7, the paper's 50 epochs.
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
_SGB_TABLE = ClassifierConfig(
    prior=GaussianPrior(0.1), kl_counting="table", kl_scale=1.0, num_samples=2, epochs=20
)
_DGB = DGBConfig(rounds=100, pnet_steps=10, gnet_steps=50, batch_size=64, validation_size=500)
_MLP_RATIOS = (2.0, 4.0, 8.0, 16.0, 32.0, 64.0)


def _small_data_sweep(epochs: int) -> CompressionSweep:
    return CompressionSweep(
        ratios=_MLP_RATIOS,
        seeds=(0, 1, 2),
        hidden=(800,),
        in_types=30,
        out_types=10,
        sgb=dataclasses.replace(_SGB_TABLE, epochs=epochs),
        dgb=_DGB,
        dense=DenseConfig(epochs=epochs),
    )


def _ablation(sweep: CompressionSweep) -> CompressionSweep:
    """The same SGB sweep at its lowest and highest ratio, two seeds, the KL counted the
    other way (per synapse <-> per type pair)."""
    other = "table" if sweep.sgb.kl_counting == "synapse" else "synapse"
    return dataclasses.replace(
        sweep,
        ratios=(min(sweep.ratios), max(sweep.ratios)),
        seeds=sweep.seeds[:2],
        models=("sgb",),
        sgb=dataclasses.replace(sweep.sgb, kl_counting=other),
    )


# MNIST-like data, the authors' shape 784-800-10 and KL (per synapse, weighted 1/n_train).
# The SGB trains with the local reparameterisation (same ELBO, lower-variance gradients);
# its individuals are evaluated as whole weight draws.
IMAGE_RATIOS = (10.0, 20.0, 50.0, 100.0, 200.0, 400.0, 700.0)
_SGB_IMAGES = dataclasses.replace(
    _SGB_TABLE, kl_counting="synapse", num_samples=1, local_reparam=True, batch_size=64
)


def _image_sweep(seeds: tuple[int, ...], epochs: int, dgb: DGBConfig) -> CompressionSweep:
    return CompressionSweep(
        ratios=IMAGE_RATIOS,
        seeds=seeds,
        hidden=(800,),
        in_types=30,
        out_types=10,
        sgb=dataclasses.replace(_SGB_IMAGES, epochs=epochs),
        dgb=dgb,
        dense=DenseConfig(epochs=epochs, batch_size=100),
    )


# cpu: 5 epochs for the SGB and the uncompressed network; the DGB's p-net sees the same
# 5 epochs (100 rounds x 30 minibatches of 100), with 50 g-net steps per round.
_IMAGE_CPU = _image_sweep(
    (0, 1, 2),
    5,
    DGBConfig(rounds=100, pnet_steps=30, gnet_steps=50, batch_size=100, validation_size=5000),
)
_IMAGE_PAPER = _image_sweep((0, 1, 2, 3, 4), 50, DGBConfig(rounds=500, gnet_steps=600))
_SMOKE = CompressionSweep(
    ratios=(4.0, 30.0),
    seeds=(0,),
    hidden=(64,),
    sgb=dataclasses.replace(_SGB_TABLE, epochs=3, eval_individuals=5),
    dgb=dataclasses.replace(_DGB, rounds=5, pnet_steps=10, gnet_steps=10),
    dense=DenseConfig(epochs=3),
)
_CIFAR_PAPER = CompressionSweep(
    ratios=(20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 1700.0),
    seeds=(0, 1, 2, 3, 4),
    hidden=(256, 128),
    conv_features=(32, 64),
    in_types=100,
    out_types=10,
    sgb=dataclasses.replace(_SGB_IMAGES, learning_rate=1e-3, batch_size=128, epochs=200),
    dgb=DGBConfig(rounds=500, gnet_steps=600, batch_size=128),
    dense=DenseConfig(batch_size=128, epochs=200),
)


def _profile(sweep: CompressionSweep, ablation: CompressionSweep | None) -> dict:
    return {"sweep": sweep, "ablation": ablation}


# profile -> dataset -> {"sweep": the sweep, "ablation": its KL ablation or None}
SWEEPS: dict[str, dict[str, dict[str, CompressionSweep | None]]] = {
    "smoke": {name: _profile(_SMOKE, None) for name in ("digits", "mnist1d")},
    "cpu": {
        "digits": _profile(_small_data_sweep(10), _ablation(_small_data_sweep(10))),
        "mnist1d": _profile(_small_data_sweep(6), _ablation(_small_data_sweep(6))),
        "fashion-mnist": _profile(_IMAGE_CPU, _ablation(_IMAGE_CPU)),
        "mnist": _profile(_IMAGE_CPU, _ablation(_IMAGE_CPU)),
    },
    "paper": {
        "digits": _profile(_small_data_sweep(50), _ablation(_small_data_sweep(50))),
        "mnist1d": _profile(_small_data_sweep(50), _ablation(_small_data_sweep(50))),
        "fashion-mnist": _profile(_IMAGE_PAPER, _ablation(_IMAGE_PAPER)),
        "mnist": _profile(_IMAGE_PAPER, _ablation(_IMAGE_PAPER)),
        "cifar10": _profile(_CIFAR_PAPER, None),
    },
}


def cell_config(
    sweep: CompressionSweep, setting: int, seed: int, rho_init: float
) -> ClassifierConfig:
    """The SGB config Figure 2's ``run_one`` trains for ``setting`` and ``seed``, from
    ``rho_init``."""
    types = (sweep.in_types, *([setting] * len(sweep.hidden)), sweep.out_types)
    return dataclasses.replace(
        sweep.sgb,
        cell_types=types,
        hidden=sweep.hidden,
        conv_features=sweep.conv_features,
        seed=seed,
        rho_init=rho_init,
    )


class SweepRecord(Record):
    """One cell of a Figure 2 sweep as ``run_one`` records it: the fields its readers use."""

    model: str
    setting: Finite
    seed: Seed
    accuracy: Accuracy
    compression: Compression
    compression_authors: Compression


class FullDgbRecord(SweepRecord):
    """A cell of ``sgb.experiments.dgb_full`` that trained all its rounds, as Figure 2's
    sweep records a DGB (``figure2_records``)."""

    nominal_ratio: NonNegative


def figure2_records(results: Record, rounds: int) -> list[FullDgbRecord]:
    """The cells of ``results`` (``sgb.experiments.dgb_full``'s ``DgbFullResults``) that
    trained all ``rounds``, as Figure 2's sweep records them: ``model`` ("dgb"),
    ``setting`` (the target ratio), ``seed``, ``compression`` (ours),
    ``compression_authors``, ``nominal_ratio`` and ``accuracy``, the test accuracy of the
    network of best validation accuracy (a fraction)."""
    return [
        FullDgbRecord(
            model="dgb",
            setting=cell.ratio,
            seed=cell.seed,
            compression=cell.compression_ours,
            compression_authors=cell.compression_authors,
            nominal_ratio=cell.nominal_ratio,
            accuracy=cell.records[-1].test_accuracy,
        )
        for cell in results.cells.values()
        if cell.records and cell.records[-1].rounds == rounds
    ]
