"""The background queue of long runs: workers that take no CPU anything else wants, a
listing of every queued run, and landing what the workers did in the repository.

    python -m sgb grid start    # one worker per core, in a worktree of HEAD (make grid)
    python -m sgb grid status   # every queued run: done, running (chunk, ETA), waiting
    python -m sgb grid land     # the workers' finished runs and unfinished states, copied in
    python -m sgb grid stop     # end the workers (a killed run resumes at its last chunk)

The workers run the experiments of ``QUEUE`` in order, at their profile, writing the
committed results of a worktree of HEAD (``../sgb-grid``, or ``$SGB_GRID``), so that
every file they write names a clean commit. Each worker is pinned to its own core, runs
XLA on one thread (``sgb.cluster.one_thread``) and is scheduled at idle priority
(``SCHED_IDLE``, in a session whose autogroup is at nice 19, ``become_idle``): it runs
only when a core would otherwise idle, so a foreground job takes the cores as if the
workers were not there. Each takes the next run no other
holds (``sgb.runlock``).

A run saves its state after every chunk (``sgb.resume``). ``land`` copies into this
checkout the queued runs' finished checkpoints (with their sidecars) and results files
(entered into the manifest), and the state file of every unfinished run, removing the
state of a run that has finished: committed, they let a fresh clone on another machine
resume every run at the chunk it had reached (``start`` makes its worktree from HEAD).

An experiment joins the queue with a function ``queued(profile, results_dir) -> Queue``
in its module (``sgb.experiments.Experiment.queued_name``): its results file and its
runs, in the order they train, each with its progress.
"""

import argparse
import importlib
import os
import shutil
import signal
import subprocess
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import NamedTuple

import pandas as pd

from sgb import cluster, gather, manifest, recording, runlock
from sgb.manifest import MAINTAINER_FLAG, add
from sgb.provenance import atomic_write
from sgb.queued import Queue, QueuedRun

REPOSITORY = Path(__file__).resolve().parent.parent  # the checkout this package lies in
GRID_ENV = "SGB_GRID"
LOGS = "grid-logs"  # in the worktree: a log and a lock per worker
# The long runs, in the order they train: (experiment, profile). Figure 3C's regime runs
# first; the other issues' long runs follow it (Figure 2's high end, then the width sweep).
# The high end's DGB cells, two hours of one core, went first once and stay there. The
# populations of the regime's genomes go before its runs: each evaluates a genome that has
# landed (20-40 min of one core against 2.5 h a run), so a genome is measured as it lands.
# Chapter 6's evolution, about 70 min of one core, goes ahead of them (it answers its
# question in one sitting, against 27 h of the regime's); its bet-hedging genomes (about
# 8 h) come last. The regime's gaits (20 s a run) go first of the regime's experiments:
# a worker stays with the regime's runs until none is left, so each start of the queue
# plays the runs landed since the last.
QUEUE = (
    ("dgb_high", "cpu"),
    ("evolution", "cpu"),
    ("regime_gait", "cpu"),
    ("regime_populations", "cpu"),
    ("regime", "cpu"),
    ("sgb_high", "cpu"),
    ("width", "cpu"),
    ("bet_hedging", "cpu"),
)


def worktree() -> Path:
    """Where the workers run: ``$SGB_GRID``, else ``sgb-grid`` beside this checkout."""
    return Path(os.environ.get(GRID_ENV, REPOSITORY.parent / "sgb-grid")).resolve()


def queues(
    results_dir: Path, queue: tuple[tuple[str, str], ...] = QUEUE
) -> Iterator[tuple[str, str, Queue]]:
    """Every experiment of ``queue``: its name, profile and ``Queue`` under
    ``results_dir``."""
    from sgb.experiments import get_experiment

    for name, profile in queue:
        experiment = get_experiment(name)
        module = importlib.import_module(f"sgb.experiments.{experiment.module}")
        yield name, profile, getattr(module, experiment.queued_name)(profile, results_dir)


# --- the workers ------------------------------------------------------------------------


AUTOGROUP = Path("/proc/self/autogroup")


def become_idle(core: int) -> None:
    """Pin this process to ``core`` and schedule it at idle priority (``SCHED_IDLE``); a
    session leader's autogroup is set to nice 19 too, where Linux groups by session.

    With autogroups (``/proc/sys/kernel/sched_autogroup_enabled``), the scheduler first
    shares the CPU between sessions at their autogroup's nice, and only within a session
    by each task's policy: a worker in a session of its own at nice 0 took two thirds of a
    core from a foreground test on this machine, idle policy and all."""
    os.sched_setaffinity(0, {core})
    os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
    if os.getsid(0) == os.getpid() and AUTOGROUP.exists():
        AUTOGROUP.write_text("19")


def work(core: int, logs: Path, main: Callable[[list[str]], int]) -> int:
    """A worker: idle on ``core``, it runs the queue's experiments in order (each by the
    command line's ``main``), each taking the runs no other worker holds, holding its
    worker lock meanwhile. A results file of an earlier design gives way to the run of
    the new one (``sgb.recording.superseding``); an experiment that fails is logged and
    the worker goes on to the next. Its exit status: the first failure's, else 0."""
    become_idle(core)
    failed = 0
    with runlock.claim(logs / f"worker-{core}") as mine, recording.superseding():
        if not mine:
            print(f"a worker on core {core} is running already", flush=True)
            return 1
        for name, profile in QUEUE:
            print(f"worker {core}: {name} --profile {profile}", flush=True)
            try:
                status = main(["reproduce", name, "--profile", profile, MAINTAINER_FLAG])
            except Exception:  # a fault of one experiment must not idle the queue
                traceback.print_exc()
                status = 1
            if status:
                print(f"worker {core}: {name} failed (status {status}); next", flush=True)
                failed = failed or status
    return failed


def workers(tree: Path) -> dict[int, int]:
    """The running workers of the worktree ``tree``: core -> process id."""
    found = {}
    for lock in sorted((tree / LOGS).glob("worker-*.lock")):
        pid = runlock.holder(lock.with_suffix(""))
        if pid is not None:
            found[int(lock.stem.removeprefix("worker-"))] = pid
    return found


def _git(*args: str, cwd: Path | None = None) -> str:
    """Run git in ``cwd`` (default: this checkout); its output, a ``RuntimeError`` if it fails."""
    done = subprocess.run(["git", *args], cwd=cwd or REPOSITORY, capture_output=True, text=True)
    if done.returncode:
        raise RuntimeError(f"git {' '.join(args)} failed: {done.stderr.strip()}")
    return done.stdout.strip()


def prepare(tree: Path, queue: tuple[tuple[str, str], ...] = QUEUE) -> None:
    """Make ``tree`` a worktree of this checkout's HEAD, refusing where that would lose
    work: while its workers run, while this checkout's results differ from HEAD, while
    ``tree`` holds work of ``queue`` not landed here (which is landed first, to be
    committed), or while ``tree`` is a folder other than a worktree that holds files."""
    if workers(tree):
        raise RuntimeError(f"workers are running in {tree}: python -m sgb grid status")
    if _git("status", "--porcelain", "--", "results"):
        raise RuntimeError(
            "this checkout's results/ differ from HEAD: commit them (or restore them) first, "
            "so that the workers start from what the repository holds"
        )
    if tree.exists():
        landed = land(tree / "results", REPOSITORY / "results", queue)
        if landed.runs or landed.results:
            raise RuntimeError(
                f"landed {len(landed.runs) + len(landed.results)} files the last workers left "
                f"in {tree}; enter its results files (python -m sgb grid land) and commit them "
                "(git add results && git commit), then start again"
            )
        if (tree / ".git").exists():
            _git("worktree", "remove", "--force", str(tree))
        elif any(path.is_file() for path in tree.rglob("*")):
            raise RuntimeError(
                f"{tree} is not a worktree of this checkout and holds files: move it away, "
                f"or set ${GRID_ENV} to another place"
            )
        else:
            shutil.rmtree(tree)  # folders only, such as a fresh clone's empty results/
    _git("worktree", "prune")
    _git("worktree", "add", "--detach", str(tree), "HEAD")


def start(count: int | None = None) -> dict[int, int]:
    """Start ``count`` workers (default: one per core) in a fresh worktree of HEAD, in
    the background; core -> process id."""
    tree = worktree()
    cores = sorted(os.sched_getaffinity(0))
    count = len(cores) if count is None else count
    if not 1 <= count <= len(cores):
        raise ValueError(f"workers must be between 1 and {len(cores)} (the cores), got {count}")
    prepare(tree)
    (tree / LOGS).mkdir(exist_ok=True)
    env = {**os.environ, "PYTHONPATH": str(tree)}
    env["XLA_FLAGS"] = cluster.one_thread(env.get("XLA_FLAGS", ""))
    started = {}
    for core in cores[:count]:
        log = open(tree / LOGS / f"worker-{core}.log", "a")  # noqa: SIM115 (the child keeps it)
        command = [sys.executable, "-m", "sgb", "grid", "work", "--core", str(core)]
        child = subprocess.Popen(
            command, cwd=tree, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True
        )
        started[core] = child.pid
    return started


def stop(tree: Path) -> dict[int, int]:
    """End the workers of ``tree`` (each run resumes at its last finished chunk)."""
    running = workers(tree)
    for pid in running.values():
        os.kill(pid, signal.SIGTERM)
    return running


# --- the listing ------------------------------------------------------------------------


def _hours(seconds: float) -> str:
    return f"{seconds / 3600:.1f} h" if seconds >= 3600 else f"{seconds / 60:.0f} min"


def time_left(per_chunk: float, chunks_left: int, into_chunk: float) -> float:
    """Seconds a run has left: ``chunks_left`` chunks of ``per_chunk`` s, less the
    ``into_chunk`` s already spent on the first of them (at most all of it)."""
    if chunks_left <= 0:
        return 0.0
    return per_chunk * (chunks_left - 1) + max(per_chunk - into_chunk, 0.0)


def _typical_s(queue: Queue) -> float | None:
    """The mean cost (s of one core, ``QueuedRun.cost_s``) of ``queue``'s finished runs,
    None where none is timed."""
    times = [r.cost_s for r in queue.runs if r.finished and r.cost_s]
    return sum(times) / len(times) if times else None


def run_left_s(run: QueuedRun, typical_s: float | None, into_chunk: float = 0.0) -> float | None:
    """Seconds ``run`` has left (0 once finished): its own chunks' pace where it has
    finished one, else the typical finished run's (``typical_s``); None where neither
    times it. ``into_chunk``: seconds already spent on its current chunk."""
    if run.finished:
        return 0.0
    chunk = run.chunks_done
    per_chunk = (
        run.spent_cost_s / chunk if chunk else (typical_s / run.chunks if typical_s else None)
    )
    return None if per_chunk is None else time_left(per_chunk, run.chunks - chunk, into_chunk)


def time_left_s(queue: Queue, into_chunks: Sequence[float] | None = None) -> float | None:
    """Seconds of one core ``queue``'s unfinished runs should take (``run_left_s`` summed);
    None where a run waits with no finished run to time it by. ``into_chunks``: per run
    of ``queue.runs``, seconds already spent on its current chunk (none by default)."""
    typical = _typical_s(queue)
    if typical is None and not all(r.finished for r in queue.runs):
        return None
    into = into_chunks or [0.0] * len(queue.runs)
    return sum(run_left_s(r, typical, i) or 0.0 for r, i in zip(queue.runs, into, strict=True))


def _spent(run: QueuedRun) -> str:
    """A finished run's wall time, and its CPU time where recorded."""
    cpu = "" if run.cpu_time_s is None else f"; CPU {_hours(run.cpu_time_s)}"
    return f"{_hours(run.wall_time_s)}{cpu}"


def _into_chunk(run: QueuedRun) -> float:
    """Seconds a running run has spent on its current chunk: since its lock was taken or
    its state last written, whichever came later (0 where neither is known)."""
    marks = [runlock.taken_at(run.checkpoint)]
    if run.state.exists():
        marks.append(run.state.stat().st_mtime)
    known = [t for t in marks if t is not None]
    return max(time.time() - max(known), 0.0) if known else 0.0


def describe(queue: Queue) -> list[str]:
    """A line per run of ``queue``: done (its wall time), running (its process, chunk and
    ETA), or waiting (where it resumes), and a summary line."""
    typical = _typical_s(queue)
    lines, into_chunks = [], []
    for r in queue.runs:
        chunk = 0 if r.finished else r.chunks_done
        pid = None if r.finished else runlock.holder(r.checkpoint)
        into = _into_chunk(r) if pid else 0.0
        into_chunks.append(into)
        if r.finished:
            what = f"done ({_spent(r)})" if r.wall_time_s else "done"
        elif pid is not None:
            remaining = run_left_s(r, typical, into)
            eta = "ETA unknown" if remaining is None else f"ETA {_hours(remaining)}"
            what = f"running (pid {pid}): chunk {chunk + 1} of {r.chunks}, {eta}"
        else:
            what = f"waiting (resumes at chunk {chunk + 1})" if chunk else "waiting"
        lines.append(f"  {r.label}: {what}")
    done = sum(r.finished for r in queue.runs)
    left = time_left_s(queue, into_chunks)
    if left is None:
        still = "time left unknown: no finished run to time the waiting ones by"
    else:
        still = f"about {_hours(left)} of one core left"
    lines.append(f"  {done} of {len(queue.runs)} runs done; {still}")
    return lines


def progress(results_dir: Path, queue: tuple[tuple[str, str], ...] = QUEUE) -> pd.DataFrame:
    """The long runs' progress in the results under ``results_dir``, one row per
    experiment of ``queue``: its results file, its runs done, part-way (a kept state) and
    in all, and the hours of one core the rest should take (``time_left_s``; blank where
    no finished run times the waiting ones)."""
    rows = []
    for name, profile, listed in queues(results_dir, queue):
        left = time_left_s(listed)
        rows.append(
            {
                "experiment": f"{name} --profile {profile}",
                "results file": listed.results.name,
                "runs done": sum(r.finished for r in listed.runs),
                "part-way": sum(not r.finished and r.chunks_done > 0 for r in listed.runs),
                "runs": len(listed.runs),
                "one-core hours left": None if left is None else left / 3600,
            }
        )
    return pd.DataFrame(rows)


# --- landing ----------------------------------------------------------------------------


def _as_committed(file: Path) -> bytes | None:
    """The bytes of ``file`` at the HEAD of the git checkout it lies in (None where it is
    not committed there, or lies in no checkout)."""
    shown = subprocess.run(
        ["git", "show", f"HEAD:./{file.name}"], cwd=file.parent, capture_output=True
    )
    return shown.stdout if shown.returncode == 0 else None


def _copy(source: Path, target: Path) -> bool:
    """Copy ``source`` over ``target`` atomically unless they hold the same bytes, or
    ``source`` is as its own checkout committed it: only what the workers wrote lands,
    never a stale copy over what this checkout has committed since."""
    data = source.read_bytes()
    if target.exists() and target.read_bytes() == data:
        return False
    if data == _as_committed(source):
        return False
    atomic_write(target, data)
    shutil.copystat(source, target)
    return True


class Landed(NamedTuple):
    """What ``land`` changed: checkpoints, sidecars and state files (copied or removed),
    and results files."""

    runs: list[Path]
    results: list[Path]


def land(source: Path, target: Path, queue: tuple[tuple[str, str], ...] = QUEUE) -> Landed:
    """Copy from the results directory ``source`` (the workers') into ``target`` what the
    runs of ``queue`` did: each finished run's checkpoint and sidecar (and its state file
    removed from ``target``), each unfinished run's latest state, the states each run
    keeps (``QueuedRun.kept``), and each queued
    experiment's results file; a finished run whose lock is still held (being saved) is
    left for the next landing."""
    changed: list[Path] = []
    results: list[Path] = []
    for _, _, queued in queues(source, queue):
        for r in queued.runs:
            if runlock.holder(r.checkpoint) is not None and r.finished:
                continue  # being written
            mine = [r.checkpoint, r.checkpoint.with_suffix(".json")] if r.finished else [r.state]
            for file in [*mine, *r.kept]:
                if file.exists():
                    there = target / file.relative_to(source)
                    if _copy(file, there):
                        changed.append(there)
            stale = target / r.state.relative_to(source)
            if r.finished and stale.exists():
                stale.unlink()
                changed.append(stale)
        there = target / queued.results.relative_to(source)
        if queued.results.exists() and _copy(queued.results, there):
            results.append(there)
    return Landed(changed, results)


def unentered(target: Path, queue: tuple[tuple[str, str], ...] = QUEUE) -> list[Path]:
    """The queued experiments' results files in ``target`` whose bytes its manifest does
    not hold: landed by a landing that stopped before entering them (a file its schema
    refused), to be entered by the next."""
    known = manifest.entries(target)
    files = [q.results for _, _, q in queues(target, queue) if q.results.exists()]
    return [f for f in files if known.get(f.relative_to(target).as_posix()) != manifest.digest(f)]


# --- the command line -------------------------------------------------------------------


def main(argv: list[str], reproduce: Callable[[list[str]], int]) -> int:
    """``python -m sgb grid start|status|land|stop|work``, a worker running each queued
    experiment by ``reproduce`` (the command line's ``main``); an exit status."""
    parser = argparse.ArgumentParser(prog="python -m sgb grid", description=__doc__.split("\n")[0])
    verbs = parser.add_subparsers(dest="verb", required=True)
    begin = verbs.add_parser("start", help="start the workers in a worktree of HEAD")
    begin.add_argument("--workers", type=int, default=None, help="default: one per core")
    verbs.add_parser("status", help="list every queued run: done, running, waiting")
    verbs.add_parser("land", help="copy the workers' finished runs and states in")
    verbs.add_parser("stop", help="end the workers")
    one = verbs.add_parser("work", help="be a worker (what start runs on each core)")
    one.add_argument("--core", type=int, required=True)
    args = parser.parse_args(argv)
    tree = worktree()
    # Brax warns, on import, that it is no longer maintained (the book says so, chapter 5)
    warnings.filterwarnings("ignore", message="Brax System", category=UserWarning)
    try:
        if args.verb == "work":
            return work(args.core, Path.cwd() / LOGS, reproduce)
        if args.verb == "start":
            for core, pid in start(args.workers).items():
                print(f"worker on core {core}: pid {pid}, log {tree / LOGS}/worker-{core}.log")
            print("python -m sgb grid status lists the queue; grid land copies its work in")
        elif args.verb == "stop":
            print(f"stopped workers {sorted(stop(tree).values())}")
        elif args.verb == "status":
            running = workers(tree)
            print(f"workers in {tree}: {running or 'none running'}")
            root = tree / "results" if tree.exists() else REPOSITORY / "results"
            for name, profile, queue in queues(root):
                print(f"{name} --profile {profile} ({queue.results.name}):")
                print("\n".join(describe(queue)))
        elif not tree.exists():
            print(f"no worktree at {tree}: no workers have run here, nothing to land")
        else:
            landed = land(tree / "results", REPOSITORY / "results")
            enter = sorted({*landed.results, *unentered(REPOSITORY / "results")})
            entered = add(enter, gather.model_of) if enter else []
            for path in landed.runs + landed.results:
                print(f"landed {path.relative_to(REPOSITORY)}")
            print(
                f"{len(entered)} results files entered into the manifest; commit what landed, "
                "with the scorecard and texts it moves: python tests/snapshot.py && "
                "git add results tests/data && git commit"
            )
    except (ValueError, RuntimeError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    return 0
