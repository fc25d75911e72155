"""The one loop over a sweep's cells (``sgb.cells.train_cells``), on a toy cell function,
alone and shared with another worker."""

import json
import threading

import pytest

from sgb import runlock
from sgb.cells import train_cells

KEYS = (lambda cell: cell, lambda record: record["cell"])


class Killed(Exception):
    """The process dies in the middle of a cell."""


def sweep(path, cells, kill_at=None):
    """Train ``cells`` (each record its square) into the JSON file ``path``, resuming
    from it; the cells trained and the records found in the file after each write."""
    trained, written = [], []

    def train(cell):
        if cell == kill_at:
            raise Killed
        trained.append(cell)
        return {"cell": cell, "value": cell**2}

    def write(records):
        path.write_text(json.dumps(records))
        written.append([r["cell"] for r in json.loads(path.read_text())])
        return path

    earlier = json.loads(path.read_text()) if path.exists() else []
    try:
        train_cells(path, cells, earlier, KEYS, train, write, "toy", progress=False)
    except Killed:
        pass
    return trained, written


def test_each_cell_is_written_as_soon_as_it_is_trained(tmp_path):
    path = tmp_path / "toy.json"
    trained, written = sweep(path, [3, 1, 2])
    assert trained == [3, 1, 2]
    assert written == [[3], [3, 1], [3, 1, 2]]
    assert json.loads(path.read_text())[1] == {"cell": 1, "value": 1}


def test_a_killed_loop_resumes_at_its_first_unfinished_cell_and_skips_the_finished(tmp_path):
    path = tmp_path / "toy.json"
    trained, written = sweep(path, [0, 1, 2, 3], kill_at=2)
    assert trained == [0, 1] and written[-1] == [0, 1]  # what it finished is on disk
    trained, written = sweep(path, [0, 1, 2, 3])
    assert trained == [2, 3]
    assert written[-1] == [0, 1, 2, 3]
    trained, written = sweep(path, [0, 1, 2, 3])  # all done: nothing trained or written
    assert trained == [] and written == []


def test_a_sweep_with_nothing_to_train_still_writes_its_missing_file(tmp_path, capsys):
    path = tmp_path / "toy.json"
    assert sweep(path, []) == ([], [[]])
    path.write_text(json.dumps([{"cell": 5, "value": 25}]))
    returned = train_cells(path, [5, 6], [{"cell": 5}], KEYS, lambda c: {"cell": c}, str, "toy")
    assert returned == path
    assert "toy: reusing the 1 cells already in" in capsys.readouterr().out


@pytest.mark.parametrize("progress", [True, False])
def test_the_records_given_are_kept_in_order_before_the_new(tmp_path, progress):
    records = [{"cell": "b"}]
    train_cells(
        tmp_path / "x.json",
        ["a", "b", "c"],
        records,
        KEYS,
        lambda c: {"cell": c},
        lambda r: tmp_path,
        "toy",
        progress,
    )
    assert [r["cell"] for r in records] == ["b", "a", "c"]


def test_shared_cells_are_each_trained_by_the_one_process_that_takes_them(tmp_path):
    """Two workers on one sweep: the cell another holds is left to it, the cells it has
    finished (found in the file when the loop reaches them) are not trained again, and
    every write keeps the other's records."""
    path = tmp_path / "sweep.json"
    path.write_text(json.dumps([{"cell": 1, "value": 1}]))  # the other worker's finished cell
    trained = []

    def reread():
        return json.loads(path.read_text())

    def train(cell):
        trained.append(cell)
        if cell == 0:  # meanwhile the other worker finishes cell 3
            path.write_text(json.dumps([*reread(), {"cell": 3, "value": 9}]))
        return {"cell": cell, "value": cell**2}

    def write(records):
        path.write_text(json.dumps(records))
        return path

    def lock(cell):
        return tmp_path / f"cell{cell}"

    held, release = threading.Event(), threading.Event()

    def other_worker():  # holds cell 2 throughout
        with runlock.claim(lock(2)):
            held.set()
            release.wait(10)

    thread = threading.Thread(target=other_worker)
    thread.start()
    held.wait(10)
    try:
        train_cells(path, [0, 1, 2, 3, 4], [], KEYS, train, write, "toy", False, (lock, reread))
    finally:
        release.set()
        thread.join()
    assert trained == [0, 4]
    assert sorted(r["cell"] for r in reread()) == [0, 1, 3, 4]
