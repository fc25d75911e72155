"""The one loop over a sweep's cells: train each cell whose record the results file does
not hold yet, in order, and write the file after each, so that a killed sweep resumes
at its first unfinished cell."""

from collections.abc import Callable, Hashable, Sequence
from pathlib import Path
from typing import TypeVar

from tqdm.auto import tqdm

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
) -> Path:
    """Train every cell of ``cells`` that no record of ``records`` (those read back from
    the results file ``path``) has finished, appending its record to ``records`` and
    calling ``write`` with them all after each; ``write`` also runs once if ``path`` is
    still missing at the end. ``keys``: a cell's key and a record's key, equal where the
    record is the cell's. Returns ``path``."""
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
        records.append(train(cell))
        write(records)
    if not Path(path).exists():
        write(records)
    return path
