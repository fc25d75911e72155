"""``sgb.experiments.fig2``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import math

import numpy as np
import pytest
from committed import RECORDS, raw

from sgb.experiments import (
    fig2,
)
from sgb.experiments import fig2 as fig2_runs


def test_figure2_ratio_tests_find_a_known_difference_at_every_ratio():
    rng = np.random.default_rng(2)
    records = [
        {
            "model": model,
            "setting": s,
            "seed": seed,
            "compression": ratio,
            "compression_authors": ratio,
            "accuracy": acc,
        }
        for s, ratio in enumerate((10.0, 100.0, 700.0))
        for model, shift in (("sgb", 0.05 if ratio > 50 else -0.05), ("dgb", 0.0))
        for seed, acc in enumerate(0.8 + shift + 0.002 * rng.standard_normal(4))
    ]
    table = fig2.figure2_ratio_tests([fig2.Fig2Record.model_validate(r) for r in records])
    assert list(table.index) == [10, 100, 700]
    expected = np.array([-5.0, 5.0, 5.0])
    assert np.all(table["95 % CI low"] < expected) and np.all(expected < table["95 % CI high"])
    assert np.all(table["p"] < 1e-3) and set(table["seeds (SGB, DGB)"]) == {"4, 4"}


def test_figure2_table_gives_each_setting_both_compressions_and_its_accuracy():
    fig2 = raw("fig2_fashion-mnist_cpu.json")["results"]
    table = fig2_runs.figure2_table(RECORDS("fig2").results)
    for model in ("dense", "sgb", "dgb"):
        ours, theirs = fig2["ours"]["summary"][model], fig2["authors"]["summary"][model]
        rows = table[table["model"] == model]
        assert rows["setting"].tolist() == ours["setting"]
        assert rows["accuracy %"].tolist() == pytest.approx([100 * m for m in ours["mean"]])
        for _, row in rows.iterrows():
            j = theirs["setting"].index(row["setting"])
            assert row["compression (authors')"] == theirs["compression"][j]
        sems = [math.nan if s is None else 100 * s for s in ours["sem"]]
        assert rows["SEM %"].tolist() == pytest.approx(sems, nan_ok=True)
