"""The background queue (``sgb.grid``): its workers run at idle priority on their own core,
its listing reads who holds a run without taking it, and a run's state landed in the
repository lets a fresh copy resume it at the chunk it had reached, bit for bit."""

import json
import os
import shutil
import subprocess
import sys
import textwrap
import time
from dataclasses import replace
from pathlib import Path

import jax
import numpy as np
import pytest
from interrupt import killed_at_chunk

from sgb import grid, manifest, recording, runlock
from sgb.experiments import regime
from sgb.rl import checkpoints, regime_runs
from sgb.rl.trainer import make_trainer

SMOKE = (("regime", "smoke"),)


def test_a_worker_runs_at_idle_priority_on_its_own_core():
    """Idle policy, one core, and (in a session of its own, where Linux groups tasks by
    session) its session's autogroup at nice 19, so the session takes no fair share."""
    core = max(os.sched_getaffinity(0))
    code = textwrap.dedent(f"""
        import os
        from pathlib import Path
        from sgb import grid
        grid.become_idle({core})
        group = Path("/proc/self/autogroup")
        nice = group.read_text().split()[-1] if group.exists() else "19"
        print(os.sched_getscheduler(0) == os.SCHED_IDLE, nice, sorted(os.sched_getaffinity(0)))
    """)
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        start_new_session=True,
    )
    assert done.stdout.split(maxsplit=2) == ["True", "19", f"[{core}]\n"]


def test_a_worker_goes_on_past_a_failing_experiment_and_supersedes_old_designs(
    tmp_path, monkeypatch
):
    """Every experiment of the queue runs, in order, with files of an earlier design giving
    way; the worker's status is the first failure's."""
    ran = []

    def main(argv):
        ran.append((argv[1], recording._superseding))
        if argv[1] == "broken":
            raise RuntimeError("a fault")
        return 3 if argv[1] == "refused" else 0

    monkeypatch.setattr(grid, "become_idle", lambda core: None)
    monkeypatch.setattr(grid, "QUEUE", (("broken", "cpu"), ("refused", "cpu"), ("fine", "cpu")))
    assert grid.work(0, tmp_path, main) == 1
    assert ran == [("broken", True), ("refused", True), ("fine", True)]
    assert not recording._superseding


def test_the_holder_of_a_run_is_read_without_taking_its_lock(tmp_path):
    run = tmp_path / "run.msgpack"
    code = textwrap.dedent(f"""
        import sys, time
        from sgb import runlock
        with runlock.claim({str(run)!r}) as mine:
            print(mine, flush=True)
            sys.stdin.readline()
    """)
    child = subprocess.Popen(
        [sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout.readline() == "True\n"
        assert runlock.holder(run) == child.pid
        with runlock.claim(run) as mine:
            assert not mine  # the child still holds it: reading it took nothing
    finally:
        child.communicate("\n")
    assert runlock.holder(run) is None
    with runlock.claim(run) as mine:
        assert mine


def test_a_running_runs_time_left_counts_the_time_into_its_chunk():
    """Three chunks of 600 s left, 200 s into the first: 1000 s + 600 s; past the first
    chunk's typical time, the rest only; none left, none."""
    assert grid.time_left(600.0, 3, 200.0) == 1600.0
    assert grid.time_left(600.0, 3, 0.0) == 1800.0
    assert grid.time_left(600.0, 3, 900.0) == 1200.0
    assert grid.time_left(600.0, 0, 50.0) == 0.0


def test_the_progress_table_counts_runs_and_times_the_rest_by_their_pace(tmp_path, monkeypatch):
    """Two runs done (1 h and 0.5 h: 0.75 h typical), one waiting (0.75 h), one at chunk 2
    of 3 after 1200 s (600 s a chunk, 600 s left): 0.75 h + 1/6 h left; a queue with no
    finished run has no estimate."""
    from sgb.queued import Queue, QueuedRun

    def run(label, finished, wall=None, chunks=1, done=0, spent=0.0):
        path = tmp_path / label
        return QueuedRun(label, path, path, chunks, finished, wall, done, spent)

    timed = Queue(
        tmp_path / "a.json",
        (
            run("one", True, 3600.0),
            run("two", True, 1800.0),
            run("three", False),
            run("four", False, chunks=3, done=2, spent=1200.0),
        ),
    )
    untimed = Queue(tmp_path / "b.json", (run("five", False),))
    monkeypatch.setattr(
        grid, "queues", lambda results, queue: [("a", "cpu", timed), ("b", "cpu", untimed)]
    )
    table = grid.progress(tmp_path).set_index("experiment")
    a, b = table.loc["a --profile cpu"], table.loc["b --profile cpu"]
    assert (a["runs done"], a["part-way"], a["runs"]) == (2, 1, 4)
    assert a["one-core hours left"] == pytest.approx(0.75 + 600 / 3600)
    assert (b["runs done"], b["runs"]) == (0, 1) and np.isnan(b["one-core hours left"])
    # where runs record their CPU time, it paces them, not the wall time (which counts
    # what the core gave to other work): the same runs at half their wall time in CPU
    halved = Queue(
        tmp_path / "a.json",
        tuple(
            replace(
                r,
                cpu_time_s=None if r.wall_time_s is None else r.wall_time_s / 2,
                spent_cpu_s=r.spent_s / 2,
            )
            for r in timed.runs
        ),
    )
    assert grid.time_left_s(halved) == pytest.approx(grid.time_left_s(timed) / 2)
    assert grid.describe(halved)[0] == "  one: done (1.0 h; CPU 30 min)"


def test_a_running_run_is_timed_from_when_its_lock_was_taken(tmp_path):
    """A one-chunk run with no state file (a cell whose result goes into the results file),
    held for 200 s of a typical 600: 400 s left, not the whole 600; the same for a chunked
    run whose state was written before the lock was taken (a resumed run)."""
    from sgb.queued import Queue, QueuedRun

    done = QueuedRun("done", tmp_path / "done", tmp_path / "done.state", 1, True, 600.0)
    cell = QueuedRun("cell", tmp_path / "cell", tmp_path / "cell.state", 1, False)
    resumed = QueuedRun(
        "resumed", tmp_path / "res", tmp_path / "res.state", 2, False, None, 1, 600.0
    )
    resumed.state.write_bytes(b"state after chunk 1")
    now = time.time()
    os.utime(resumed.state, (now - 3600, now - 3600))
    with runlock.claim(cell.checkpoint) as mine, runlock.claim(resumed.checkpoint) as theirs:
        assert mine and theirs
        for run in (cell, resumed):
            os.utime(f"{run.checkpoint}.lock", (now - 200, now - 200))
        lines = grid.describe(Queue(tmp_path / "a.json", (done, cell, resumed)))
    pid = os.getpid()
    assert lines[1] == f"  cell: running (pid {pid}): chunk 1 of 1, ETA 7 min"
    assert lines[2] == f"  resumed: running (pid {pid}): chunk 2 of 2, ETA 7 min"


def _curve(results: Path, name: str) -> tuple[list[float], list[np.ndarray]]:
    """The learning curve and parameters of checkpoint ``name`` under ``results``."""
    _, params, _, meta = checkpoints.load(results / "rl" / "checkpoints" / name)
    return meta["eval_returns"], [np.asarray(x) for x in jax.tree_util.tree_leaves(params)]


def test_a_landed_state_lets_a_fresh_copy_resume_its_run_bit_for_bit(tmp_path, monkeypatch, capsys):
    """Workers' results (a run killed in its second chunk) are landed in the repository; a
    fresh copy of it resumes the run at its second chunk, and the run ends as one never
    stopped; landed again, the finished run replaces its state, and the state the 16-type
    run keeps after its first chunk lands with it."""
    monkeypatch.setattr(regime_runs, "KEPT_CHUNKS", {16: (1,)})
    config = regime_runs.RUNS["smoke"]
    vanilla = regime_runs.run_config(config, config.runs[0])
    name = config.runs[0].checkpoint("smoke")
    uninterrupted = tmp_path / "uninterrupted"
    regime.run("smoke", uninterrupted)

    workers, repository = tmp_path / "worktree", tmp_path / "repository"
    trainer = make_trainer(vanilla.step_settings())
    with killed_at_chunk(trainer, 2, monkeypatch), pytest.raises(KeyboardInterrupt):
        regime.run("smoke", workers)

    landed = grid.land(workers, repository, SMOKE)
    state = repository / "rl" / "checkpoints" / name.replace(".msgpack", ".state.npz")
    assert landed.runs == [state] and landed.results == []
    listing = grid.describe(next(grid.queues(repository, SMOKE))[2])
    assert listing[0] == "  vanilla seed 0: waiting (resumes at chunk 2)"

    clone = tmp_path / "clone"
    shutil.copytree(repository, clone)
    capsys.readouterr()
    regime.run("smoke", clone)
    assert "vanilla seed 0 (1/2): resumed" in capsys.readouterr().out
    resumed, fresh = _curve(clone, name), _curve(uninterrupted, name)
    assert resumed[0] == fresh[0]
    for a, b in zip(resumed[1], fresh[1], strict=True):
        np.testing.assert_array_equal(a, b)

    again = grid.land(clone, repository, SMOKE)
    assert not state.exists() and state in again.runs
    kept = repository / "rl" / "checkpoints" / "ant_regime_k16_s0_smoke.chunk1.npz"
    assert kept in again.runs and kept.exists()
    assert again.results == [repository / "rl" / "regime_ant_smoke.json"]
    listing = grid.describe(next(grid.queues(repository, SMOKE))[2])
    assert [line.split(": ")[1].split(" (")[0] for line in listing[:2]] == ["done", "done"]


def test_landing_skips_a_file_the_workers_left_as_their_checkout_committed_it(tmp_path):
    """A worktree's results file still as its HEAD has it (the workers never wrote it) does
    not land over this checkout's newer one; once the workers write it, it lands."""
    tree = tmp_path / "worktree"
    (tree / "results").mkdir(parents=True)
    stale = tree / "results" / "sweep.json"
    stale.write_text('{"old": 1}\n')
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-C", str(tree)]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "add", "."], check=True)
    subprocess.run([*git, "commit", "-qm", "results"], check=True)
    here = tmp_path / "repository" / "sweep.json"
    here.parent.mkdir()
    here.write_text('{"newer": 2}\n')
    assert not grid._copy(stale, here) and here.read_text() == '{"newer": 2}\n'
    stale.write_text('{"written by a worker": 3}\n')
    assert grid._copy(stale, here) and here.read_text() == stale.read_text()


def test_a_folder_left_where_the_worktree_goes_gives_way_unless_it_holds_files(
    tmp_path, monkeypatch
):
    """The workers' worktree replaces a folder of empty folders (such as a fresh clone's
    listing leaves), and is refused where the folder holds a file that is not a worktree's."""
    repository = tmp_path / "repository"
    (repository / "results").mkdir(parents=True)
    (repository / "results" / "sweep.json").write_text('{"committed": 1}\n')
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-C", str(repository)]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "add", "."], check=True)
    subprocess.run([*git, "commit", "-qm", "results"], check=True)
    monkeypatch.setattr(grid, "REPOSITORY", repository)

    tree = tmp_path / "tree"
    (tree / "results" / "rl").mkdir(parents=True)
    grid.prepare(tree, SMOKE)
    assert (tree / ".git").is_file()
    assert (tree / "results" / "sweep.json").read_text() == '{"committed": 1}\n'
    grid.prepare(tree, SMOKE)  # a worktree already: made anew
    assert (tree / "results" / "sweep.json").exists()

    other = tmp_path / "other"
    (other / "results").mkdir(parents=True)
    (other / "notes.txt").write_text("mine\n")
    with pytest.raises(RuntimeError, match="not a worktree"):
        grid.prepare(other, SMOKE)
    assert (other / "notes.txt").read_text() == "mine\n"


def test_a_results_file_landed_but_not_entered_is_entered_by_the_next_landing(tmp_path):
    """A landing that stopped after copying a results file (its schema refused it) leaves
    bytes the manifest does not hold: the next landing enters them, whether or not it
    copies anything; once entered, nothing is left."""
    results = tmp_path / "rl" / "regime_ant_smoke.json"
    results.parent.mkdir()
    results.write_text('{"landed": 1}\n')
    assert grid.unentered(tmp_path, SMOKE) == [results]
    entered = {"sha256": {"rl/regime_ant_smoke.json": manifest.digest(results)}}
    (tmp_path / manifest.NAME).write_text(json.dumps(entered))
    assert grid.unentered(tmp_path, SMOKE) == []
