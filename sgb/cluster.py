"""Sweeps shared out over several workers on Ray: a local cluster or an existing one.

The sweeps whose runs each take a lock (``sgb.runlock``) and resume from a state file
(Figure 3, the authors' regime, the full-budget DGB) can be run by several processes at
once: each trains the runs no other holds. ``run_workers(task, workers)`` runs ``task``
in ``workers`` Ray tasks, each asking for one CPU and, where the cluster has GPUs, one
GPU. A task whose worker dies is retried (``retries`` times); its retry takes the killed
run again, whose lock died with its process, and resumes it from its state file. Every
run keeps its own provenance in its checkpoint, and the last worker to finish writes
the sweep's results file from all of them.

Every run of such a sweep takes one XLA thread, in a worker or in this process alike
(``one_thread``): XLA's multi-threaded CPU kernels add in another order, and a PPO run
carries that last-bit difference into other returns, so the thread count would
otherwise decide a run's numbers. On a local cluster each worker is also pinned to one
core:
``benchmarks/bench_parallel.py`` measured two such runs at once on this 2-core machine
at 2.04 times the throughput of one run alone (Ant PPO), 1.58 times for a Figure 2 cell.
Ray is an optional extra (``pip install 'sgb-companion[cluster]'``).
"""

import importlib.util
import os
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")
ONE_THREAD = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"


def one_thread(flags: str) -> str:
    """``flags`` (an ``XLA_FLAGS`` value) with XLA's CPU kernels held to one thread."""
    return flags if ONE_THREAD in flags else f"{flags} {ONE_THREAD}".strip()


def available() -> bool:
    """Whether Ray is installed."""
    return importlib.util.find_spec("ray") is not None


def local_workers() -> int:
    """Workers of a local cluster: one per core this process may use."""
    return len(os.sched_getaffinity(0))


def run_workers(
    task: Callable[[], T], workers: int, address: str | None = None, retries: int = 3
) -> list[T]:
    """``task()`` in ``workers`` Ray tasks at once; their results, in order.

    ``address=None`` starts a local cluster of ``workers`` CPUs, each task pinned to its
    own core with one XLA thread; otherwise the tasks run on the cluster at ``address``
    (``"auto"``: the one this machine belongs to), each asking for one CPU and one GPU
    where the cluster has GPUs. A task whose worker dies is run again, up to ``retries``
    times."""
    # plain checks: this module stays light, as every worker unpickles its tasks from it
    if not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    if not isinstance(retries, int) or retries < 0:
        raise ValueError(f"retries must be an integer >= 0, got {retries!r}")
    if not available():
        raise RuntimeError("Ray is not installed: pip install 'sgb-companion[cluster]'")
    import ray

    local = address is None
    ray.init(
        address=address,
        num_cpus=workers if local else None,
        include_dashboard=False,
        runtime_env={"env_vars": {"XLA_FLAGS": one_thread(os.environ.get("XLA_FLAGS", ""))}},
        log_to_driver=True,
    )
    try:
        gpus = 1 if ray.cluster_resources().get("GPU", 0) > 0 else 0
        cores = sorted(os.sched_getaffinity(0))

        def worker(i: int) -> T:
            if local:
                os.sched_setaffinity(0, {cores[i % len(cores)]})
            return task()

        remote = ray.remote(num_cpus=1, num_gpus=gpus, max_retries=retries)(worker)
        return ray.get([remote.remote(i) for i in range(workers)])
    finally:
        ray.shutdown()
