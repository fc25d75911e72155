"""``sgb.experiments.innate_start``: its rows of the scorecard, its texts and its tables, on the
committed results and on inputs with known effects."""

import numpy as np
import pytest
from committed import RECORDS, raw

from sgb import verdicts
from sgb.experiments import (
    innate_start,
    innate_start_supervised,
)


def test_innate_start_rows_find_a_head_start_and_rule_out_none():
    """Five seeds: the mean network's start learns 30 % more over the budget than the
    fresh network of its seed, a random individual's as much as the fresh one."""
    rng = np.random.default_rng(8)
    runs = []
    for seed in range(5):
        fresh = 2000 + 300 * rng.standard_normal()
        for genome, start, gain in ((None, "fresh", 0.0), ("g", "mean", 0.3), ("g", "random", 0.0)):
            auc = fresh * (1 + gain + 0.02 * rng.standard_normal()) if genome else fresh
            runs.append(
                {"genome": genome, "start": start, "seed": seed, "auc": auc}
                | {"eval_steps": [0, 5_000_000], "eval_returns": [0.0, auc]}
                | {"return_at": {f: auc for f in ("0", "0.25", "0.5", "1")}}
            )
    selections = [{"genome": "g", "individual_means": [1000.0] * 100}]
    results = {"complete": True, "runs": runs, "selections": selections}
    results["summary"] = innate_start.summarise(runs)
    results = innate_start.InnateStartResults.model_validate(results)
    mean, random = innate_start.innate_start_rows(results)
    assert mean.verdict in verdicts.IN_DIRECTION and mean.test.estimate == pytest.approx(
        0.3, abs=0.03
    )
    assert mean.setting == "g, from its mean network"
    assert random.verdict == verdicts.CONTRADICTED and "random" in random.setting
    # on the new task: a head start at 50 steps (15 and 10 points), none at 100
    starts = (("individual", 0.0, 0.75, 0.8), ("mean", 0.0, 0.7, 0.8), ("fresh", 0.1, 0.6, 0.8))

    twin_rng = np.random.default_rng(8)

    def runs() -> list[dict]:
        noise = 0.005 * twin_rng.standard_normal((len(starts), 2))  # each network's own curve
        return [
            {"start": s, "steps": [0, 50, 100], "accuracy": [a0, a + e50, b + e100]}
            for (s, a0, a, b), (e50, e100) in zip(starts, noise, strict=True)
        ]

    records = [{"runs": runs()} for _ in range(6)]
    twin = {"dataset": "digits", "genome_classes": [0, 1, 2, 3, 4], "records": records}
    twin["summary"] = innate_start_supervised.summarise(records)
    twin = innate_start_supervised.InnateStartSupervisedResults.model_validate(twin)
    rows = {r.setting: r for r in innate_start_supervised.innate_supervised_rows(twin)}
    task = "digits classes 5-9 (genome on 0-4)"
    assert len(rows) == 4  # two budgets past the start, two starts
    early = rows[f"{task}, from individual, after 50 steps"].test
    assert early.estimate == pytest.approx(15, abs=1.5)
    # 10 points, measured to within a point or so, against a stand-in of 1 point
    assert rows[f"{task}, from mean, after 50 steps"].verdict == verdicts.LARGER
    assert rows[f"{task}, from individual, after 100 steps"].verdict == verdicts.CONTRADICTED


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
