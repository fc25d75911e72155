"""``sgb.experiments.mean_gap``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

from committed import RECORDS, raw

from sgb.experiments import (
    mean_gap,
)


def test_mean_gap_table_shows_each_cell_in_percent():
    gap = raw("mean_gap_fashion-mnist_cpu.json")["results"]
    table = mean_gap.mean_gap_table(RECORDS("mean_gap").results)
    assert len(table) == len(gap["summary"])
    first = gap["summary"][0]
    assert table.loc[0, "gap (points)"] == (
        f"{100 * first['gap']:.1f} ± {100 * first['gap_sem']:.1f}"
    )
    assert table.loc[0, "hidden types"] == first["setting"]
