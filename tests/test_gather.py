"""``sgb.gather``: the committed results read by experiment as their models, and the
scorecard gathered from every experiment's evidence; the way `book/run.md` tells a reader
to read them works as written."""

import re
from pathlib import Path

import pytest

from sgb import claims, gather, grid, verdicts
from sgb.experiments import EXPERIMENTS, fig3
from sgb.paths import committed_results
from sgb.schemas import ResultsFile

RUN_MD = Path(__file__).resolve().parent.parent / "book" / "run.md"


def test_every_declared_file_is_read_as_the_model_of_its_experiment():
    """Every declared results file is committed, and read as its experiment's model, but
    those of queued experiments whose first run has not landed yet."""
    records = gather.records()
    queued = {name for name, _ in grid.QUEUE}
    for name, source in gather.sources().items():
        for part, file in source.files.items():
            record = records.get(name, part)
            if record is None:
                assert name in queued, f"{file} is declared but not committed"
                continue
            assert isinstance(record, source.model) and isinstance(record, ResultsFile)
            assert gather.model_of(file) is source.model
    assert records("fig3", "ant") is records("fig3", "ant")  # each file read once
    with pytest.raises(ValueError, match="declares no results file 'walker'"):
        records("fig3", "walker")
    with pytest.raises(ValueError, match="no experiment or benchmark declares"):
        gather.model_of("rl/fig3_walker_cpu.json")


def test_the_scorecard_gathers_each_experiment_once_in_its_order(tmp_path):
    assert set(gather.EVIDENCE) <= {n for n, e in EXPERIMENTS.items() if e.evidence}
    assert len(set(gather.EVIDENCE)) == len(gather.EVIDENCE)
    # no results at all: the untestable claims alone, each with its reason
    rows = gather.scorecard(tmp_path)
    assert [r.key for r in rows] == list(gather.UNTESTABLE)
    assert all(r.test is None and r.decide for r in rows)


def test_the_readers_recipe_in_run_md_runs_as_written():
    text = RUN_MD.read_text()
    (code,) = [c for c in re.findall(r"```python\n(.*?)```", text, re.S) if "gather" in c]
    scope: dict = {}
    exec(compile(code, str(RUN_MD), "exec"), scope)  # the book's own example, as written
    assert isinstance(scope["sweep"], fig3.Fig3)
    assert scope["returns"] == [r.final_return for r in scope["sweep"].results.runs]
    assert scope["rows"] and all(r.verdict for r in scope["rows"])


def test_the_committed_scorecard_gives_every_claim_one_verdict():
    rows = gather.scorecard(committed_results())
    assert {r.verdict for r in rows} <= set(verdicts.VERDICTS)
    keys = {r.key.split(".")[0] + "." + r.key.split(".")[1] for r in rows}
    assert {"fig2.sgb_better_high", "fig4e.r_legs", "fig5.population_beats_mean"} <= keys
    assert len(claims.table(rows)) == len(rows)  # every row names what it tests
    for r in rows:
        if r.verdict == verdicts.INCONCLUSIVE:
            assert r.decide  # the budget that would decide is named
        if r.verdict == verdicts.NOT_TESTABLE:
            assert r.test is None and r.decide  # the reason
