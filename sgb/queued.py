"""An experiment's queued runs, as the background queue (``sgb.grid``) lists and lands
them: each run's checkpoint, state file, chunks and progress, and the experiment's
results file."""

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class QueuedRun:
    """One run of a queued experiment: its name; its checkpoint (a ``.msgpack`` with its
    ``.json`` sidecar, or for a run whose result goes into the results file, the path its
    lock is taken on); its state file while unfinished; its chunks; how many it has
    finished and their wall time (s); once finished, its wall time (s); the same two in
    CPU time (s) where the run records it (``None`` where not); and the files it keeps
    besides (``kept``: states part-way through, landed as they appear)."""

    label: str
    checkpoint: Path
    state: Path
    chunks: int
    finished: bool
    wall_time_s: float | None = None
    chunks_done: int = 0
    spent_s: float = 0.0
    kept: tuple[Path, ...] = ()
    cpu_time_s: float | None = None
    spent_cpu_s: float | None = None

    @property
    def cost_s(self) -> float | None:
        """What the finished run took of one core: its CPU time where recorded, else its
        wall time (more, at idle priority, by the time the core gave to other work)."""
        return self.wall_time_s if self.cpu_time_s is None else self.cpu_time_s

    @property
    def spent_cost_s(self) -> float:
        """``cost_s`` of its finished chunks."""
        return self.spent_s if self.spent_cpu_s is None else self.spent_cpu_s


@dataclass(frozen=True)
class Queue:
    """A queued experiment at one profile: its results file and its runs, in order."""

    results: Path
    runs: tuple[QueuedRun, ...]


def known_sum(times: list[float | None]) -> float | None:
    """The sum of ``times`` (s), or None where one of them was not recorded."""
    return None if None in times else sum(times)


def run_lock(results: Path, name: str) -> Path:
    """The path the lock of run ``name`` of the results file ``results`` is taken on, for
    a run whose result goes into that file (a cell of a sweep, a genome's population)."""
    return results.with_name(f"{results.stem}_{name}")


def file_run(label: str, results: Path, name: str, record: dict | None) -> QueuedRun:
    """A run of one chunk whose result is ``record`` (``None`` until it is written) in the
    results file ``results``, locked at ``run_lock``; its CPU time where the record has
    it."""
    lock = run_lock(results, name)
    wall = None if record is None else record["wall_time_s"]
    cpu = None if record is None else record.get("cpu_time_s")
    state = lock.with_suffix(".state.npz")
    return QueuedRun(label, lock, state, 1, record is not None, wall, cpu_time_s=cpu)
