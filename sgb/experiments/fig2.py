"""Figure 2: innate test accuracy of DGB and SGB against compression ratio.

``run(profile, out_dir, dataset=...)`` sweeps SGB, DGB and the uncompressed
network over compression ratios and seeds on one dataset and writes
``fig2_<dataset>_<profile>.json`` with provenance (one file per profile, so a smoke
run never overwrites committed results; see ``sgb.provenance.results_file``).

KL choice (see the book's chapter 4): the KL to a N(0, 0.1^2) prior is counted
once per type pair (``kl_counting="table"``, the genome view) and weighted
1/n_train. Counting it per expanded synapse, as Bayes by backprop does, is
run as an ablation at two ratios at the cpu profile.
"""

import dataclasses
import time
from pathlib import Path
from typing import Any

from sgb.data import load
from sgb.experiments import check_profile
from sgb.priors import GaussianPrior
from sgb.provenance import provenance, results_file, write_results
from sgb.supervised import (
    ClassifierConfig,
    DenseConfig,
    SweepConfig,
    compression_sweep,
    crossovers,
    summarise_sweep,
)

_SGB = ClassifierConfig(
    prior=GaussianPrior(0.1), kl_counting="table", kl_scale=1.0, num_samples=2, epochs=20
)
_DGB = DenseConfig(epochs=20, rounds=8, fit_steps=100, fit_batch=4096, gnet_learning_rate=1e-2)
_MLP_RATIOS = (2.0, 4.0, 8.0, 16.0, 32.0, 64.0)


def _small_data_sweep(epochs: int) -> SweepConfig:
    return SweepConfig(
        ratios=_MLP_RATIOS,
        seeds=(0, 1, 2),
        hidden=(800,),
        in_types=30,
        out_types=10,
        sgb=dataclasses.replace(_SGB, epochs=epochs),
        dgb=dataclasses.replace(_DGB, epochs=epochs),
    )


def _ablation(sweep: SweepConfig) -> SweepConfig:
    """The same SGB sweep at its lowest and highest ratio, two seeds, the KL counted per
    synapse."""
    return dataclasses.replace(
        sweep,
        ratios=(min(sweep.ratios), max(sweep.ratios)),
        seeds=sweep.seeds[:2],
        models=("sgb",),
        sgb=dataclasses.replace(sweep.sgb, kl_counting="synapse"),
    )


_SMOKE = SweepConfig(
    ratios=(4.0, 30.0),
    seeds=(0,),
    hidden=(256,),
    sgb=dataclasses.replace(_SGB, epochs=3, eval_individuals=5),
    dgb=dataclasses.replace(_DGB, epochs=3, rounds=2, fit_steps=50),
)
_MNIST_PAPER = SweepConfig(
    ratios=(10.0, 20.0, 50.0, 100.0, 200.0, 400.0, 700.0),
    seeds=(0, 1, 2, 3, 4),
    hidden=(800,),
    in_types=30,
    out_types=10,
    sgb=dataclasses.replace(_SGB, learning_rate=5e-5, batch_size=64, epochs=50),
    dgb=dataclasses.replace(_DGB, batch_size=64, epochs=50, rounds=25, fit_steps=200),
)
_CIFAR_PAPER = SweepConfig(
    ratios=(20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 1700.0),
    seeds=(0, 1, 2, 3, 4),
    hidden=(256, 128),
    conv_features=(32, 64),
    in_types=100,
    out_types=10,
    sgb=dataclasses.replace(_SGB, learning_rate=1e-3, batch_size=128, epochs=200),
    dgb=dataclasses.replace(_DGB, batch_size=128, epochs=200, rounds=50, fit_steps=200),
)

# profile -> dataset -> (sweep, KL ablation or None)
PROFILES: dict[str, dict[str, tuple[SweepConfig, SweepConfig | None]]] = {
    "smoke": {name: (_SMOKE, None) for name in ("digits", "mnist1d")},
    "cpu": {
        "digits": (_small_data_sweep(10), _ablation(_small_data_sweep(10))),
        "mnist1d": (_small_data_sweep(6), _ablation(_small_data_sweep(6))),
        "mnist": (dataclasses.replace(_MNIST_PAPER, seeds=(0, 1, 2)), None),
    },
    "paper": {
        "digits": (_small_data_sweep(50), _ablation(_small_data_sweep(50))),
        "mnist1d": (_small_data_sweep(50), _ablation(_small_data_sweep(50))),
        "mnist": (_MNIST_PAPER, None),
        "cifar10": (_CIFAR_PAPER, None),
    },
}


def sweep_results(
    dataset: str, sweep: SweepConfig, ablation: SweepConfig | None, progress: bool = True
) -> dict[str, Any]:
    """Records, per-model summary and SGB/DGB crossovers of a sweep (and of its ablation)."""
    data = load(dataset, seed=0)
    records = compression_sweep(data, sweep, progress)
    summary = summarise_sweep(records)
    out: dict[str, Any] = {
        "dataset": dataset,
        "sizes": [int(data.x_train.shape[-1]), *sweep.hidden, data.num_classes],
        "records": records,
        "summary": summary,
        "summary_mean_network": summarise_sweep(
            [r for r in records if r["model"] == "sgb"], "mean_network"
        ),
        "crossovers": crossovers(summary) if {"sgb", "dgb"} <= set(summary) else [],
    }
    if ablation is not None:
        out["ablation_records"] = compression_sweep(data, ablation, progress)
    return out


def run(profile: str, out_dir: Path, dataset: str = "digits", progress: bool = True) -> Path:
    """Run the sweep of ``profile`` on ``dataset`` and write its results with provenance."""
    check_profile(profile)
    if dataset not in PROFILES[profile]:
        raise ValueError(
            f"dataset {dataset!r} has no {profile} profile; choose one of "
            f"{sorted(PROFILES[profile])}"
        )
    sweep, ablation = PROFILES[profile][dataset]
    path = results_file(out_dir, f"fig2_{dataset}", profile)
    start = time.perf_counter()
    results = sweep_results(dataset, sweep, ablation, progress)
    record = provenance(
        {"sweep": sweep, "ablation": ablation},
        profile,
        list(sweep.seeds),
        time.perf_counter() - start,
    )
    return write_results(path, results, record)
