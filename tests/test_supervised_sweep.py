"""Compression sweeps: one ratio function for every model, sweep summaries, the fig2 smoke run."""

import time

import jax
import numpy as np
import pytest

from sgb import supervised
from sgb.compression import compression_ratio, dense_param_count, tree_param_count
from sgb.data import Dataset, load
from sgb.experiments import fig2
from sgb.provenance import read_results
from sgb.supervised import (
    ClassifierConfig,
    DenseConfig,
    SweepConfig,
    compression_of,
    crossovers,
    dense_sizes,
    make_model,
    run_one,
    setting_for_ratio,
    summarise_sweep,
    train_dense,
)


def test_sgb_and_dgb_ratios_come_from_one_function_and_count_real_parameters(monkeypatch):
    sizes = (64, 40, 10)
    calls = []

    def spy(uncompressed, compressed):
        calls.append((uncompressed, compressed))
        return compression_ratio(uncompressed, compressed)

    monkeypatch.setattr(supervised, "compression_ratio", spy)
    sgb_ratio = compression_of("sgb", sizes, 6, 30, 10)
    dgb_ratio = compression_of("dgb", sizes, 5, 30, 10)
    assert [c[0] for c in calls] == [dense_param_count(sizes)] * 2

    x = np.zeros((1, 64), np.float32)
    sgb_model = make_model(ClassifierConfig(hidden=(40,), cell_types=(30, 6, 10)), 10)
    sgb_params = sgb_model.init({"params": jax.random.key(0), "sample": jax.random.key(1)}, x)
    assert calls[0][1] == tree_param_count(sgb_params["params"])
    data = Dataset("toy", np.zeros((8, 64), np.float32), np.zeros(8, np.int32), x, x[:, 0], 10)
    _, dgb_params, _ = train_dense(
        DenseConfig(hidden=(40,), gnet_hidden=(5,), epochs=1, batch_size=8, rounds=1, fit_steps=1),
        data,
        progress=False,
    )
    biases = sum(np.size(v["bias"]) for v in dgb_params["params"].values())
    assert calls[1][1] == tree_param_count(dgb_params["genome"]) + biases
    assert sgb_ratio == pytest.approx(dense_param_count(sizes) / calls[0][1])
    assert dgb_ratio == pytest.approx(dense_param_count(sizes) / calls[1][1])


def test_setting_for_ratio_is_nearest_on_a_log_scale():
    sizes = (64, 800, 10)
    for kind in ("sgb", "dgb"):
        setting = setting_for_ratio(kind, sizes, 8.0, 30, 10)
        best = abs(np.log(compression_of(kind, sizes, setting, 30, 10) / 8.0))
        for other in (setting - 1, setting + 1):
            assert best <= abs(np.log(compression_of(kind, sizes, other, 30, 10) / 8.0))
    with pytest.raises(ValueError, match="ratio"):
        setting_for_ratio("sgb", sizes, -1.0, 30, 10)


def test_summary_and_crossover_of_synthetic_records():
    records = [
        {"model": m, "setting": s, "seed": seed, "compression": c, "accuracy": a + 0.01 * seed}
        for m, rows in {
            "sgb": [(1, 10.0, 0.80), (2, 100.0, 0.70)],
            "dgb": [(1, 10.0, 0.90), (2, 100.0, 0.50)],
        }.items()
        for s, c, a in rows
        for seed in (0, 1)
    ]
    summary = summarise_sweep(records)
    assert summary["sgb"]["compression"] == [10.0, 100.0]
    np.testing.assert_allclose(summary["dgb"]["mean"], [0.905, 0.505])
    np.testing.assert_allclose(summary["dgb"]["sem"], [0.005, 0.005])
    # difference -0.1 at log10 = 1 and +0.2 at log10 = 2: zero a third of the way
    (point,) = crossovers(summary)
    assert point == pytest.approx(10 ** (1 + 1 / 3))


def test_conv_classifiers_run_on_images():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(32, 8, 8, 3)).astype(np.float32)
    y = rng.integers(0, 3, 32).astype(np.int32)
    data = Dataset("images", x, y, x, y, 3)
    assert dense_sizes(x.shape[1:], (4,), (12,), 3) == (64, 12, 3)
    sweep = SweepConfig(
        hidden=(12,),
        conv_features=(4,),
        in_types=8,
        out_types=3,
        sgb=ClassifierConfig(epochs=1, batch_size=16, eval_individuals=2),
        dgb=DenseConfig(epochs=1, batch_size=16, rounds=1, fit_steps=2),
    )
    for kind, setting in (("sgb", 4), ("dgb", 3)):
        record = run_one(kind, setting, 0, data, sweep)
        assert 0.0 <= record["accuracy"] <= 1.0 and record["compression"] > 1.0


def test_uncompressed_baseline_learns_digits():
    data = load("digits")
    model, params, _ = train_dense(DenseConfig(hidden=(64,), epochs=15), data, progress=False)
    assert supervised.dense_accuracy(model, params, data.x_test, data.y_test) > 0.9


def test_fig2_smoke_sweep_runs_end_to_end_in_under_a_minute(tmp_path):
    start = time.perf_counter()
    path = fig2.run("smoke", tmp_path, dataset="digits", progress=False)
    assert time.perf_counter() - start < 60
    payload = read_results(path)
    assert path.name == "fig2_digits_smoke.json"
    assert payload["provenance"]["profile"] == "smoke"
    results = payload["results"]
    assert {"sgb", "dgb", "dense"} == set(results["summary"])
    for kind in ("sgb", "dgb"):
        assert len(results["summary"][kind]["compression"]) == 2
    accuracies = [r["accuracy"] for r in results["records"]]
    assert max(accuracies) > 0.5  # above chance (0.1) for the uncompressed network at least
    with pytest.raises(ValueError, match="cifar10"):
        fig2.run("smoke", tmp_path, dataset="cifar10")
