"""One process per run: a lock beside a run's output, so that several processes can work
through the same sweep, each taking the runs no other holds.

``claim(path)`` takes an exclusive, non-blocking ``flock`` on ``path`` + ``.lock`` and
yields whether it got it; ``exclusive(path)`` waits for it (for a read-modify-write of a
file that several processes update, such as a sweep's results file). The operating
system releases a lock when its process ends, killed or not, so a run left by a dead
process is free for the next one to resume.
"""

import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def _open(path: str | Path) -> int:
    lock = Path(f"{path}.lock")
    lock.parent.mkdir(parents=True, exist_ok=True)
    return os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)


@contextmanager
def claim(path: str | Path) -> Iterator[bool]:
    """Hold the lock of ``path`` for the ``with`` block if no other process holds it;
    yields ``True`` if this process holds it, ``False`` if another does."""
    fd = _open(path)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        yield True
    finally:
        os.close(fd)


@contextmanager
def exclusive(path: str | Path) -> Iterator[None]:
    """Hold the lock of ``path`` for the ``with`` block, waiting while another process does."""
    fd = _open(path)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)
