"""Sweeps shared out on a local Ray cluster of 2 workers: a worker killed mid-run is
retried, its run resumed, and the results are those of one process.

The sweep here has the protocol of the real ones (a lock per run, ``sgb.runlock``; a
state file a killed run resumes from; a finished run not redone), with runs cheap
enough for a test: four runs of three steps, a quarter of a second each.
"""

import json
import os
import signal
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from sgb import cluster, runlock
from sgb.__main__ import worker_count

ray = pytest.importorskip("ray")
RUNS, STEPS = 4, 3


def toy_sweep(out: Path, kill_marker: Path | None = None) -> dict[int, float]:
    """Every run no other process holds: run i sums ``STEPS`` seeded normals, one step a
    second, saving its state after each. With ``kill_marker`` absent, the process
    training run 1 kills itself after its first step (and leaves the marker)."""
    for i in range(RUNS):
        result = out / f"run{i}.json"
        with runlock.claim(result) as mine:
            if not mine or result.exists():
                continue
            state_file = out / f"run{i}.state.json"
            state = {"step": 0, "value": 0.0, "pids": []}
            if state_file.exists():
                state = json.loads(state_file.read_text())
            state["pids"].append(os.getpid())
            while state["step"] < STEPS:
                state["value"] += float(np.random.default_rng([i, state["step"]]).normal())
                state["step"] += 1
                state_file.write_text(json.dumps(state))
                if kill_marker is not None and i == 1 and not kill_marker.exists():
                    kill_marker.touch()
                    os.kill(os.getpid(), signal.SIGKILL)
                time.sleep(0.25)
            result.write_text(json.dumps(state))
            state_file.unlink()
    return finished(out)


def finished(out: Path) -> dict[int, float]:
    return {
        i: json.loads((out / f"run{i}.json").read_text())["value"]
        for i in range(RUNS)
        if (out / f"run{i}.json").exists()
    }


@pytest.fixture(scope="module", autouse=True)
def _pickled_by_value():
    # the workers cannot import this test module: ship its functions with the tasks
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    yield
    ray.cloudpickle.unregister_pickle_by_value(sys.modules[__name__])


def _pids(out: Path) -> set[int]:
    return {
        pid for i in range(RUNS) for pid in json.loads((out / f"run{i}.json").read_text())["pids"]
    }


def test_two_workers_share_a_sweep_and_a_killed_one_resumes_to_one_process_results(
    tmp_path,
):
    alone, shared = tmp_path / "alone", tmp_path / "shared"
    alone.mkdir(), shared.mkdir()
    expected = toy_sweep(alone)
    marker = tmp_path / "killed"
    returned = cluster.run_workers(lambda: toy_sweep(shared, marker), workers=2, retries=2)
    assert marker.exists()  # a worker did die mid-run, and its task was run again
    assert finished(shared) == expected and len(expected) == RUNS
    assert len(returned) == 2 and expected in returned  # the last to finish saw every run
    killed = json.loads((shared / "run1.json").read_text())
    assert len(killed["pids"]) == 2  # the killed run was taken up again, from its state
    others = {
        pid for i in (0, 2, 3) for pid in json.loads((shared / f"run{i}.json").read_text())["pids"]
    }
    assert len(others | set(killed["pids"])) >= 2  # more than one process trained runs


def test_only_sweeps_that_share_their_runs_take_workers():
    assert worker_count("bbb", "cpu", None, None) == 1
    assert worker_count("fig3", "smoke", None, None) == 1
    assert worker_count("fig3", "cpu", None, None) == cluster.local_workers()
    assert worker_count("fig3", "cpu", 1, None) == 1
    with pytest.raises(ValueError, match="does not share its runs"):
        worker_count("fig2", "cpu", 2, None)
