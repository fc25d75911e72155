"""``sgb.experiments.dgb_full``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import pytest
from committed import RECORDS, raw

from sgb.experiments import (
    dgb_full,
)
from sgb.supervised_sweep import figure2_records


def test_the_full_budget_dgb_table_and_records_read_the_same_cells():
    """Every cell is a row of the table; the finished ones (all the configured rounds) are
    Figure 2 records, with the table's accuracy, compression and nominal ratio."""
    payload = raw("dgb_full_fashion-mnist_cpu.json")
    table = dgb_full.dgb_full_table(RECORDS("dgb_full"))
    assert len(table) == len(payload["results"]["cells"])
    rounds = payload["provenance"]["config"]["dgb"]["rounds"]
    finished = table[table["rounds"] == rounds].set_index(["target ratio", "seed"])
    records = figure2_records(RECORDS("dgb_full").results, rounds)
    assert len(records) == len(finished) > 0
    for r in records:
        row = finished.loc[(r.setting, r.seed)]
        assert 100 * r.accuracy == pytest.approx(row["test accuracy %"])
        assert r.compression == row["compression (ours)"]
        assert r.nominal_ratio == row["nominal ratio (paper's axis)"]
