"""``sgb.runlock``: paths only, one holder at a time, and locks that do not nest."""

import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from sgb import runlock

ROOT = Path(__file__).resolve().parents[1]
HOLD = """
import sys, time
from sgb import runlock
with runlock.exclusive(sys.argv[1]):
    print("held", flush=True)
    time.sleep(60)
"""


@pytest.mark.parametrize("path", [None, 123, b"run", ["run"]])
def test_a_lock_takes_a_path_only(tmp_path, monkeypatch, path):
    monkeypatch.chdir(tmp_path)
    for lock in (runlock.claim, runlock.exclusive):
        with pytest.raises(TypeError, match="path must be a path"):
            with lock(path):
                pass
    with pytest.raises(ValueError, match="path must not be empty"):
        with runlock.claim(""):
            pass
    assert list(tmp_path.iterdir()) == []  # no None.lock, 123.lock or .lock


@pytest.mark.parametrize("outer", [runlock.claim, runlock.exclusive])
@pytest.mark.parametrize("inner", [runlock.claim, runlock.exclusive])
def test_a_nested_lock_of_the_same_path_is_an_error_not_a_deadlock(tmp_path, outer, inner):
    run = tmp_path / "run.json"
    with outer(run):
        with pytest.raises(RuntimeError, match="already holds the lock .*run.json.lock"):
            with inner(os.path.relpath(run)):  # the same file by another name
                pass
        with runlock.claim(tmp_path / "other.json") as mine:  # another path nests
            assert mine
    with inner(run):  # released: free again
        pass


def test_another_thread_waits_for_the_lock_and_another_process_is_refused_it(tmp_path):
    run = tmp_path / "run.json"
    taken, order = threading.Event(), []

    def second():
        taken.wait()
        with runlock.exclusive(run):
            order.append("second")

    thread = threading.Thread(target=second)
    thread.start()
    with runlock.exclusive(run):
        taken.set()
        thread.join(timeout=0.5)
        assert thread.is_alive()  # waiting, not refused
        order.append("first")
    thread.join(timeout=10)
    assert order == ["first", "second"]

    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(run)], cwd=ROOT, stdout=subprocess.PIPE, text=True
    )
    try:
        assert holder.stdout.readline() == "held\n"
        with runlock.claim(run) as mine:
            assert not mine
    finally:
        holder.kill()
        holder.wait()
    with runlock.claim(run) as mine:  # the killed process's lock is released
        assert mine
