"""Compression sweeps: one ratio function for every model, resumable runs, summaries, the
fig2 smoke run."""

import numpy as np
import pytest

from sgb.classifiers import dense_sizes
from sgb.compression import compression
from sgb.data import Dataset, load
from sgb.dgb import DGBConfig
from sgb.experiments import fig2
from sgb.provenance import read_results
from sgb.supervised import ClassifierConfig, DenseConfig, dense_accuracy, train_dense
from sgb.supervised_sweep import (
    CompressionSweep,
    crossovers,
    run_one,
    summarise_compression,
    sweep_cells,
    sweep_summary,
)


def test_summary_and_crossover_of_synthetic_records():
    records = [
        {
            "model": m,
            "setting": s,
            "seed": seed,
            "compression": c,
            "compression_authors": 3 * c,
            "accuracy": a + 0.01 * seed,
        }
        for m, rows in {
            "sgb": [(1, 10.0, 0.80), (2, 100.0, 0.70)],
            "dgb": [(1, 10.0, 0.90), (2, 100.0, 0.50)],
        }.items()
        for s, c, a in rows
        for seed in (0, 1)
    ]
    summary = summarise_compression(records)
    assert summary["sgb"]["compression"] == [10.0, 100.0]
    np.testing.assert_allclose(summary["dgb"]["mean"], [0.905, 0.505])
    np.testing.assert_allclose(summary["dgb"]["sem"], [0.005, 0.005])
    # difference -0.1 at log10 = 1 and +0.2 at log10 = 2: zero a third of the way
    (point,) = crossovers(summary)
    assert point == pytest.approx(10 ** (1 + 1 / 3))
    both = sweep_summary(records)
    assert both["authors"]["crossovers"] == pytest.approx([3 * point])


def test_conv_classifiers_run_on_images():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(32, 8, 8, 3)).astype(np.float32)
    y = rng.integers(0, 3, 32).astype(np.int32)
    data = Dataset("images", x, y, x, y, 3)
    assert dense_sizes(x.shape[1:], (4,), (12,), 3) == (64, 12, 3)
    sweep = CompressionSweep(
        hidden=(12,),
        conv_features=(4,),
        in_types=8,
        out_types=3,
        sgb=ClassifierConfig(epochs=1, batch_size=16, eval_individuals=2),
        dgb=DGBConfig(rounds=1, pnet_steps=2, batch_size=16, gnet_steps=2, validation_size=8),
        dense=DenseConfig(epochs=1, batch_size=16),
    )
    for kind, setting in (("sgb", 4), ("dgb", 3)):
        record = run_one(kind, setting, 0, data, sweep)
        assert 0.0 <= record["accuracy"] <= 1.0
        assert record["compression"] == compression(kind, (64, 12, 3), setting, 8, 3)
        assert record["compression_authors"] > record["compression"]
        assert record["cpu_time_s"] > 0  # what the cell cost, beside its wall time


def test_uncompressed_baseline_learns_digits():
    data = load("digits")
    model, params, _ = train_dense(DenseConfig(hidden=(64,), epochs=15), data, progress=False)
    assert dense_accuracy(model, params, data.x_test, data.y_test) > 0.9


def test_fig2_smoke_sweep_runs_end_to_end_and_resumes(tmp_path, monkeypatch):
    path = fig2.run("smoke", tmp_path, dataset="digits", progress=False)
    payload = read_results(path)
    assert path.name == "fig2_digits_smoke.json"
    assert payload["provenance"]["profile"] == "smoke"
    results = payload["results"]
    for convention in ("ours", "authors"):
        assert {"sgb", "dgb", "dense"} == set(results[convention]["summary"])
        for kind in ("sgb", "dgb"):
            assert len(results[convention]["summary"][kind]["compression"]) == 2
    accuracies = [r["accuracy"] for r in results["records"]]
    assert max(accuracies) > 0.5  # above chance (0.1) for the uncompressed network at least

    # a rerun finds every cell done and trains nothing
    def fail(*args, **kwargs):
        raise AssertionError("a finished cell was run again")

    monkeypatch.setattr(fig2, "run_one", fail)
    assert read_results(fig2.run("smoke", tmp_path, dataset="digits"))["results"] == results
    with pytest.raises(ValueError, match="cifar10"):
        fig2.run("smoke", tmp_path, dataset="cifar10")


def test_resume_refuses_results_of_another_config(tmp_path, monkeypatch):
    path = tmp_path / "fig2_digits_smoke.json"
    path.write_text('{"provenance": {"config": {"other": 1}}, "results": {}}')
    with pytest.raises(ValueError, match="another config"):
        fig2.run("smoke", tmp_path, dataset="digits")


def test_fashion_mnist_main_setting_counts_the_kl_per_synapse():
    sweep, ablation = fig2.PROFILES["cpu"]["fashion-mnist"].values()
    assert sweep.sgb.kl_counting == "synapse" and ablation.sgb.kl_counting == "table"
    assert sweep.hidden == (800,) and (sweep.in_types, sweep.out_types) == (30, 10)
    assert len(sweep.ratios) >= 7 and len(sweep.seeds) == 3 and sweep.dgb.rounds >= 100
    sizes = (784, 800, 10)
    cells = sweep_cells(sweep, sizes)
    authors = [compression(k, sizes, s, 30, 10, "authors") for k, s, _ in cells if k != "dense"]
    assert min(authors) < 25 and max(authors) >= 1000


def test_the_parallel_benchmarks_figure2_worker_trains_the_cpu_sweeps_cells():
    """``benchmarks/bench_parallel.py``'s Figure 2 worker picks the Fashion-MNIST ``cpu``
    sweep itself (its source run up to loading the data)."""
    import importlib.util
    from pathlib import Path

    from sgb import supervised_sweep

    path = Path(__file__).resolve().parent.parent / "benchmarks" / "bench_parallel.py"
    spec = importlib.util.spec_from_file_location("bench_parallel", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    source = bench.fig2_worker()
    namespace: dict = {}
    exec(source[: source.index("data = load(")], namespace)
    assert namespace["sweep"] is supervised_sweep.SWEEPS["cpu"]["fashion-mnist"]["sweep"]
