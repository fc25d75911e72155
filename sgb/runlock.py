"""One process per run: a lock beside a run's output, so that several processes can work
through the same sweep, each taking the runs no other holds.

``claim(path)`` takes an exclusive, non-blocking ``flock`` on ``path`` + ``.lock`` and
yields whether it got it; ``exclusive(path)`` waits for it (for a read-modify-write of a
file that several processes update, such as a sweep's results file). The operating
system releases a lock when its process ends, killed or not, so a run left by a dead
process is free for the next one to resume.

``holder(path)`` says which process holds the lock of ``path``, without taking it (from
Linux's ``/proc/locks``), so that a listing of a sweep cannot take a run from a worker;
``taken_at(path)`` when the lock was last taken.

``path`` is a ``str`` or an ``os.PathLike``, anything else a ``TypeError``. Locks do not
nest: taking the lock of a path inside a ``with`` block that holds it (``claim`` or
``exclusive``, in the same thread) is a ``RuntimeError``, where it would otherwise
deadlock (``exclusive``) or report the lock as another's (``claim``). Another thread of
the process is refused it, or waits for it, as another process is.
"""

import fcntl
import os
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from sgb import validation

_held = threading.local()  # .files: (device, inode) of each lock file this thread holds


def _held_files() -> set[tuple[int, int]]:
    if not hasattr(_held, "files"):
        _held.files = set()
    return _held.files


def _lock_file(path: str | os.PathLike) -> Path:
    """The lock file of ``path``: ``path`` + ``.lock``."""
    return Path(f"{os.fspath(validation.path('path', path))}.lock")


@contextmanager
def _locked(path: str | os.PathLike, blocking: bool) -> Iterator[bool]:
    """Open the lock file of ``path`` and ``flock`` it; yield whether it is held. A
    ``RuntimeError`` if this thread holds it already."""
    lock = _lock_file(path)
    lock.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        stat = os.fstat(fd)
        identity = (stat.st_dev, stat.st_ino)
        if identity in _held_files():
            raise RuntimeError(f"this thread already holds the lock {lock}; locks do not nest")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX if blocking else fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        os.utime(fd)  # the lock file's mtime: when the lock was last taken (``taken_at``)
        _held_files().add(identity)
        try:
            yield True
        finally:
            _held_files().discard(identity)
    finally:
        os.close(fd)


@contextmanager
def claim(path: str | os.PathLike) -> Iterator[bool]:
    """Hold the lock of ``path`` for the ``with`` block if no other process holds it;
    yields ``True`` if this process holds it, ``False`` if another does."""
    with _locked(path, blocking=False) as mine:
        yield mine


@contextmanager
def exclusive(path: str | os.PathLike) -> Iterator[None]:
    """Hold the lock of ``path`` for the ``with`` block, waiting while another process does."""
    with _locked(path, blocking=True):
        yield


PROC_LOCKS = Path("/proc/locks")


def holder(path: str | os.PathLike) -> int | None:
    """The process id holding the lock of ``path`` (``claim``, ``exclusive``), ``None`` if
    none does or this system has no ``/proc/locks``; takes no lock itself."""
    lock = _lock_file(path)
    try:
        stat = lock.stat()
        table = PROC_LOCKS.read_text()
    except OSError:
        return None
    inode = f"{os.major(stat.st_dev):02x}:{os.minor(stat.st_dev):02x}:{stat.st_ino}"
    for line in table.splitlines():
        # "1: FLOCK  ADVISORY  WRITE 1234 08:01:5678 0 EOF"; a blocked waiter's id has "->"
        fields = line.split()
        if len(fields) >= 6 and fields[1] == "FLOCK" and "->" not in fields[0]:
            if fields[5] == inode:
                return int(fields[4])
    return None


def taken_at(path: str | os.PathLike) -> float | None:
    """When the lock of ``path`` was last taken (s since the epoch: its lock file's mtime),
    ``None`` if it never was."""
    lock = _lock_file(path)
    try:
        return lock.stat().st_mtime
    except OSError:
        return None
