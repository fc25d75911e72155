"""``sgb.experiments.fig3``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import pytest
from committed import RECORDS, raw

from sgb.experiments import fig3 as fig3_runs


def test_fig3_table_holds_every_scored_row_of_both_sweeps_unchanged():
    payloads = [raw(f"rl/fig3_{env}_cpu.json") for env in ("ant", "halfcheetah")]
    table = fig3_runs.fig3_table([RECORDS("fig3", env) for env in ("ant", "halfcheetah")])
    expected = [(p["results"]["env"], row) for p in payloads for row in _scored(p)]
    assert len(table) == len(expected)
    for (_, got), (env, row) in zip(table.iterrows(), expected, strict=True):
        assert got["body"] == env and got["genome"] == fig3_runs.FIG3_GENOMES[row["settings"]]
        k = row["cell_types"]
        assert got["cell types"] == ("vanilla" if k is None else str(k))
        assert got["mean return"] == row["mean_return"] and got["seeds"] == row["n_seeds"]


def _scored(payload: dict) -> list[dict]:
    """A Figure 3 file's summary rows as the book scores them, read from its JSON."""
    return payload["results"].get("summary_last_two", payload["results"]["summary"])


def test_fig3_summary_prefers_the_last_two_score():
    ant = raw("rl/fig3_ant_cpu.json")
    summary = fig3_runs.fig3_summary(fig3_runs.Fig3.model_validate(ant))
    assert [row.model_dump() for row in summary] == ant["results"]["summary_last_two"]
    del ant["results"]["summary_last_two"]
    summary = fig3_runs.fig3_summary(fig3_runs.Fig3.model_validate(ant))
    assert [row.model_dump() for row in summary] == ant["results"]["summary"]


def test_fig3_seeds_average_to_the_summary_of_their_sweep():
    """Each setting's seeds, as fractions of vanilla, have the summary's fraction as mean."""
    for env in ("ant", "halfcheetah"):
        seeds = fig3_runs.fig3_seeds(RECORDS("fig3", env))
        for row in _scored(raw(f"rl/fig3_{env}_cpu.json")):
            if row["cell_types"] is None:
                continue
            mine = [
                s["fraction"]
                for s in seeds
                if (s["settings"], s["cell_types"]) == (row["settings"], row["cell_types"])
            ]
            assert len(mine) == row["n_seeds"]
            assert sum(mine) / len(mine) == pytest.approx(row["fraction"])
