"""``sgb.experiments.dgb_full``: its table on the committed results, and Figure 2's high
end (``dgb_high`` and ``sgb_high``): its networks, and its cells through the background
queue."""

import shutil

import pytest
from committed import RECORDS, raw

from sgb import budget, grid
from sgb.compression import authors_nominal_width, compression, setting_for_ratio
from sgb.experiments import dgb_full, sgb_full
from sgb.provenance import read_results
from sgb.supervised_sweep import figure2_records


def test_the_full_budget_dgb_table_and_records_read_the_same_cells():
    """Every cell is a row of the table; the finished ones (all the configured rounds) are
    Figure 2 records, with the table's accuracy, compression and nominal ratio."""
    payload = raw("dgb_full_fashion-mnist_cpu.json")
    table = dgb_full.dgb_full_table(RECORDS("dgb_full").results)
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


def test_the_high_ends_cells_are_the_networks_of_the_papers_axis():
    """On Fashion-MNIST's 784-800-10 network, each target ratio of the high end gives the
    network it is said to: the DGB the g-net width the authors' script builds for its
    nominal 1,500x and 3,000x, the SGB 3, 5, 10 and 20 hidden types (30 input types, 10
    output types); the SGB's authors' count then exceeds the paper's 3,000x at 5 types."""
    sizes = (784, 800, 10)
    for nominal, target in dgb_full.HIGH_NOMINAL.items():
        width = setting_for_ratio("dgb", sizes, target, 30, 10, layout="authors")
        assert width == authors_nominal_width(sizes, nominal)
    for types, target in sgb_full.HIGH_TYPES.items():
        assert setting_for_ratio("sgb", sizes, target, 30, 10) == types
    assert compression("sgb", sizes, 5, 30, 10, "authors") > 3000


def test_the_high_end_lands_through_the_queue_and_resumes_a_cell_at_its_chunk(
    tmp_path, monkeypatch
):
    """A worker killed after a DGB cell's first chunk leaves its state and a results file
    with that chunk; landed, the queue lists the cell as resuming at chunk 2; a copy of the
    repository finishes it, training only the second chunk, and the SGB cell; landed again,
    both are done and the state is gone."""
    high = (("dgb_high", "smoke"), ("sgb_high", "smoke"))
    workers, repository = tmp_path / "worktree", tmp_path / "repository"
    real = dgb_full.train_with_budget

    def killed_after_one(cell, data, state):
        yield next(real(cell, data, state))
        raise KeyboardInterrupt

    with monkeypatch.context() as patch:
        patch.setattr(dgb_full, "train_with_budget", killed_after_one)
        with pytest.raises(KeyboardInterrupt):
            dgb_full.run_high("smoke", workers, progress=False)
    landed = grid.land(workers, repository, high)
    (cell,) = dgb_full.HIGH_PROFILES["smoke"].cells()
    path = repository / "dgb_high_digits_smoke.json"
    assert landed.runs == [dgb_full.state_file(path, cell)] and landed.results == [path]
    dgb_queue, sgb_queue = (queue for _, _, queue in grid.queues(repository, high))
    assert grid.describe(dgb_queue)[0].endswith(": waiting (resumes at chunk 2)")
    assert not sgb_queue.runs[0].finished

    clone = tmp_path / "clone"
    shutil.copytree(repository, clone)
    trained = []
    monkeypatch.setattr(budget, "train_dgb", _counting(budget.train_dgb, trained))
    dgb_full.run_high("smoke", clone, progress=False)
    sgb_full.run_high("smoke", clone, progress=False)
    assert len(trained) == 1  # the second chunk alone
    again = grid.land(clone, repository, high)
    assert not dgb_full.state_file(path, cell).exists()
    assert len(again.results) == 2
    for _, _, queue in grid.queues(repository, high):
        assert all(r.finished and r.wall_time_s > 0 for r in queue.runs)
    records = read_results(path)["results"]["cells"][dgb_full.cell_name(cell)]["records"]
    assert [r["rounds"] for r in records] == [2, 4]


def _counting(function, calls: list):
    def counted(*args, **kwargs):
        calls.append(args)
        return function(*args, **kwargs)

    return counted
