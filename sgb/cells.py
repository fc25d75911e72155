"""The one loop over a sweep's cells: train each cell whose record the results file does
not hold yet, in order, and write the file after each, so that a killed sweep resumes
at its first unfinished cell; shared, several processes work through the cells at once,
each taking the cells no other holds (``sgb.runlock``)."""

from collections.abc import Callable, Hashable, Sequence
from pathlib import Path
from typing import TypeVar

from tqdm.auto import tqdm

from sgb import runlock

Cell = TypeVar("Cell")
Record = TypeVar("Record")


def train_cells(
    path: Path,
    cells: Sequence[Cell],
    records: list[Record],
    keys: tuple[Callable[[Cell], Hashable], Callable[[Record], Hashable]],
    train: Callable[[Cell], Record],
    write: Callable[[list[Record]], Path],
    desc: str,
    progress: bool = True,
    shared: tuple[Callable[[Cell], Path], Callable[[], list[Record]]] | None = None,
) -> Path:
    """Train every cell of ``cells`` that no record of ``records`` (those read back from
    the results file ``path``) has finished, appending its record to ``records`` and
    calling ``write`` with them all after each; ``write`` also runs once if ``path`` is
    still missing at the end. ``keys``: a cell's key and a record's key, equal where the
    record is the cell's. Returns ``path``.

    ``shared``: (a cell's lock path, the records the file holds now) for cells that
    several processes share: each cell is trained under its lock by whichever process
    takes it first, and the file is read again and written under its own lock."""
    cell_key, record_key = keys
    done = {record_key(r) for r in records}
    todo = [cell for cell in cells if cell_key(cell) not in done]
    if progress and records:
        print(
            f"{desc}: reusing the {len(records)} cells already in {path}; "
            f"{len(todo)} left to train",
            flush=True,
        )
    for cell in tqdm(todo, desc=desc, disable=not progress):
        if shared is None:
            records.append(train(cell))
            write(records)
            continue
        lock, reread = shared
        with runlock.claim(lock(cell)) as mine:
            with runlock.exclusive(path):
                records[:] = reread()
            if not mine or cell_key(cell) in {record_key(r) for r in records}:
                continue
            record = train(cell)
            with runlock.exclusive(path):
                records[:] = [*reread(), record]
                write(records)
    if not Path(path).exists():
        write(records)
    return path
