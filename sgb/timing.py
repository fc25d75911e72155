"""What a piece of work cost: its wall time and this process's CPU time, in seconds.

    with timed() as spent:
        train(...)
    record |= spent  # {"wall_time_s": ..., "cpu_time_s": ...}

The wall time counts a pause (SIGSTOP) and, for a worker at idle priority, the time its
core gave to other work; the CPU time counts neither, and counts every thread of the
process: it is what the work took of the machine.
"""

import contextlib
import time
from collections.abc import Iterator


@contextlib.contextmanager
def timed() -> Iterator[dict[str, float]]:
    """Time the work within: on leaving, the dict it yielded holds ``wall_time_s`` and
    ``cpu_time_s`` (s, rounded to 0.01)."""
    spent: dict[str, float] = {}
    wall, cpu = time.perf_counter(), time.process_time()
    yield spent
    spent["wall_time_s"] = round(time.perf_counter() - wall, 2)
    spent["cpu_time_s"] = round(time.process_time() - cpu, 2)
