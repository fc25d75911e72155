"""The results-reading layer (``sgb.results``) gives the committed files' own values."""

import json
import math
import shutil

import pytest

from sgb import gather, manifest, results, schemas
from sgb.experiments import (
    dgb_budget,
    dgb_full,
    fig4_5,
    innate_start,
    innate_start_supervised,
    mean_gap,
    rl_spread,
    sgb_full,
)
from sgb.experiments import fig2 as fig2_runs
from sgb.experiments import fig3 as fig3_runs
from sgb.experiments import regime as regime_runs
from sgb.paths import committed_results
from sgb.supervised_sweep import figure2_records
from sgb.validation import CorruptFile

RECORDS = gather.records()  # the committed results, read by experiment


def raw(name: str) -> dict:
    """A committed results file as plain JSON, read without the package."""
    return json.loads((committed_results() / name).read_text())


def test_load_reads_the_committed_file_as_its_record_and_names_a_missing_one(tmp_path):
    record = results.load("rl/fig3_ant_cpu.json", fig3_runs.Fig3)
    assert isinstance(record.results.runs[0], fig3_runs.Fig3Run)
    assert record.model_dump(exclude_unset=True) == raw("rl/fig3_ant_cpu.json")
    assert results.path("theory_cpu.json") == committed_results() / "theory_cpu.json"
    assert results.load("absent.json", fig3_runs.Fig3, tmp_path, missing_ok=True) is None
    with pytest.raises(FileNotFoundError, match="absent.json"):
        results.load("absent.json", fig3_runs.Fig3, tmp_path)


def _committed_files() -> list[str]:
    """The names of every results file under the committed results that the manifest keeps."""
    root = committed_results()
    names = (p.relative_to(root).as_posix() for p in root.rglob("*.json"))
    return sorted(n for n in names if manifest.covers(n))


def test_every_committed_results_file_matches_the_manifest_and_its_schema():
    """What the book's build reads: every file is in the manifest as its run wrote it (and
    the manifest names no other), and parses under its schema."""
    names = _committed_files()
    assert len(names) >= 20 and "rl/bench_rl.json" in names
    assert sorted(manifest.entries(committed_results())) == names
    for name in names:
        assert results.load(name, gather.model_of(name)).model_dump(exclude_unset=True) == raw(name)
    with pytest.raises(ValueError, match="no experiment or benchmark declares"):
        gather.model_of("rl/unknown_ant_cpu.json")


def test_the_manifest_refuses_a_one_number_edit_of_a_committed_file(tmp_path):
    """A copy of the committed Figure 5 file and the manifest reads as the committed one;
    one return changed by hand (to 1e308, which swings a verdict) and it is refused, by name."""
    shutil.copy(committed_results() / manifest.NAME, tmp_path)
    (tmp_path / "rl").mkdir()
    copy = tmp_path / "rl" / "fig5_ant_cpu.json"
    shutil.copy(committed_results() / "rl" / "fig5_ant_cpu.json", copy)
    assert [r.key for r in gather.scorecard(tmp_path)][:2] == ["fig5.population_beats_mean"] * 2
    payload = raw("rl/fig5_ant_cpu.json")
    first = payload["results"]["authors_protocol"]["individuals"][0][0]
    text = copy.read_text()
    assert text.count(repr(first)) == 1
    copy.write_text(text.replace(repr(first), "1e308"))
    with pytest.raises(CorruptFile, match="differs from its entry in") as error:
        gather.scorecard(tmp_path)
    assert error.value.path == copy
    assert "fig5_ant_cpu.json" in str(error.value) and "--maintainer-write-committed" in str(
        error.value
    )
    (tmp_path / manifest.NAME).unlink()  # a directory without a manifest: the schema refuses it
    with pytest.raises(CorruptFile, match=r"individuals\[0\]\[0\] = 1e\+308: Input should be less"):
        gather.scorecard(tmp_path)


def test_provenance_line_names_profile_seeds_commits_date_and_wall_time():
    payload = raw("fig2_fashion-mnist_cpu.json")
    record = payload["provenance"]
    line = results.provenance_line(RECORDS("fig2"))
    assert "\n" not in line
    assert line.startswith(f"profile {record['profile']}, seeds {record['seeds']}, ")
    assert all(commit[:10] in line for commit in record["git_commits"])
    commits = ["9dbd713a4e" + "0" * 30, "9dbd713a4e" + "0" * 30 + "+dirty", "c7ecc8e69f" * 4]
    mixed = {**payload, "provenance": {**record, "git_commits": commits}}
    several = results.provenance_line(schemas.ResultsFile.model_validate(mixed))
    assert several.count("9dbd713a4e,") == 1 and "9dbd713a4e+dirty" in several  # each once
    assert "c7ecc8e69f" in several
    assert record["date"][:10] in line
    assert f"{record['wall_time_s'] / 60:.0f} min on {record['backend']}" in line


@pytest.mark.parametrize(
    ("seconds", "shown"), [(313.1, "5 min"), (59.6, "60 s"), (28236.56, "7.8 h")]
)
def test_provenance_line_gives_the_wall_time_in_a_readable_unit(seconds, shown):
    made = {"profile": "cpu", "seeds": [0], "git_commit": "0123456789abcdef", "backend": "cpu"}
    made |= {"config": {}, "date": "2026-12-01T20:18:05+00:00", "wall_time_s": seconds}
    line = results.provenance_line(schemas.ResultsFile.model_validate({"provenance": made}))
    assert line == f"profile cpu, seeds [0], commit 0123456789, 2026-12-01, {shown} on cpu"


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


def test_regime_and_spread_tables_are_the_runs_of_their_files():
    regime = raw("rl/regime_ant_cpu.json")
    table = regime_runs.regime_table(RECORDS("regime"))
    assert list(table.columns) == list(regime_runs.REGIME_COLUMNS.values())
    assert table["final return"].tolist() == [r["final_return"] for r in regime["results"]["runs"]]
    spread = raw("rl/spread_ant_cpu.json")
    table = rl_spread.spread_table(RECORDS("spread"))
    runs = spread["results"]["runs"]
    assert table["sigma trained"].tolist() == [r["sigma_trained"] for r in runs]
    assert table["paired t(99)"].tolist() == [r["paired_test"]["t"] for r in runs]


def test_innate_start_tables_name_every_start_with_no_list_cells():
    """One row per summary row; the fresh network named; the supervised curve's accuracy
    in % at each step, the Ant's returns as mean ± SEM text."""
    ant = raw("rl/innate_start_ant_cpu.json")
    table = innate_start.innate_start_table(RECORDS("innate_start"))
    summary = ant["results"]["summary"]
    assert len(table) == len(summary)
    assert "none (fresh network)" in set(table["genome"])
    first = summary[1]
    assert table.loc[1, "return at 1"] == (
        f"{first['return_at_1']:.0f} ± {first['return_at_1_sem']:.0f}"
    )
    sup = raw("innate_start_supervised_fashion-mnist_cpu.json")
    table = innate_start_supervised.innate_start_supervised_table(
        RECORDS("innate_start_supervised")
    )
    row = sup["results"]["summary"][0]
    last = row["steps"][-1]
    shown = table.loc[0, f"step {last} (% accuracy)"]
    assert shown.startswith(f"{100 * row['accuracy'][-1]:.1f} ± ")
    assert not any(isinstance(v, list) for v in table.to_numpy().ravel())


def test_mean_gap_table_shows_each_cell_in_percent():
    gap = raw("mean_gap_fashion-mnist_cpu.json")["results"]
    table = mean_gap.mean_gap_table(RECORDS("mean_gap").results)
    assert len(table) == len(gap["summary"])
    first = gap["summary"][0]
    assert table.loc[0, "gap (points)"] == (
        f"{100 * first['gap']:.1f} ± {100 * first['gap_sem']:.1f}"
    )
    assert table.loc[0, "hidden types"] == first["setting"]


def test_fig45_statistics_are_the_files_tests():
    fig4, fig5 = raw("rl/fig4_ant_cpu.json"), raw("rl/fig5_ant_cpu.json")
    table = fig4_5.fig45_statistics(RECORDS("fig4"), RECORDS("fig5")).set_index("test")
    legs = table.loc["Pearson r, normal body vs long legs"]
    assert legs["statistic"] == fig4["results"]["legs"]["r"]
    assert table.loc["Pearson r, slippery vs low gravity", "p"] == fig4["results"]["niches"]["p"]
    protocol = fig5["results"]["authors_protocol"]
    authors = table.loc["one-sample t (the authors' protocol)"]
    assert authors["statistic"] == protocol["t"]
    assert authors["mean network's return"] == protocol["mean_network_ci99"][0]
    assert math.isnan(legs["mean network's return"])


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


def test_dgb_budget_table_has_one_row_per_record():
    budget = raw("dgb_budget_fashion-mnist_cpu.json")["results"]
    table = dgb_budget.dgb_budget_table(RECORDS("dgb_budget").results)
    assert table["rounds"].tolist() == [r["rounds"] for r in budget["records"]]
    assert table["its test %"].tolist() == pytest.approx(
        [100 * r["test_accuracy"] for r in budget["records"]]
    )


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


def test_the_full_budget_sgb_table_averages_each_setting_over_its_cells():
    payload = raw("sgb_full_fashion-mnist_cpu.json")
    table = sgb_full.sgb_full_table(RECORDS("sgb_full"))
    cells = list(payload["results"]["cells"].values())
    assert table["seeds"].sum() == len(cells)
    for _, row in table.iterrows():
        variant, hidden = row["variant"], row["hidden types"]
        mine = [c for c in cells if c["variant"] == variant and c["setting"] == hidden]
        assert row["seeds"] == len(mine)
        mean = 100 * sum(c["accuracy"] for c in mine) / len(mine)
        assert row["individuals %"] == pytest.approx(mean)
        assert row["sigma, layer 0"] == pytest.approx(
            sum(c["layers"][0]["mean_sigma"] for c in mine) / len(mine)
        )


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
