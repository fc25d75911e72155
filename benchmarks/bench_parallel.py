"""Do two runs at once pay on this machine? Throughput of one run alone (all cores)
against two runs side by side, each pinned to its own core with one XLA thread.

For each workload (an Ant PPO run at the Figure 3 ``cpu`` settings; a Figure 2 SGB cell
at the Fashion-MNIST ``cpu`` width), in one sitting:

1. one run alone, free to use every core;
2. two runs at once, each under ``taskset`` on one core, with XLA's intra-op thread pool
   limited to one thread.

The figure of merit is work per second summed over the runs that go at once (PPO:
training env-steps/s after the compiling chunk; Figure 2: training examples/s after
the first epoch). ``ratio`` = two-at-once / alone: above 1, two at once pay.

Usage: ``python benchmarks/bench_parallel.py [--workloads ppo_ant fig2_cell]
[--ppo-steps 400000] [--rounds 2] [--out results/bench_parallel.json]`` (the file is
written with provenance).
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from sgb.provenance import provenance
from sgb.recording import write_results

ONE_THREAD = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"

PPO_WORKER = """
import json, sys
from dataclasses import replace
from sgb.rl.sweep import sweep_config
from sgb.rl.ppo import train
config = replace(sweep_config("ant", "cpu").ppo, total_steps={steps}, num_evals=3)
result = train(config, seed=0, progress=False)
print(json.dumps({{"rate": result.train_steps_per_s}}))
"""


FIG2_WORKER = """
import json, time
from sgb.data import load
from sgb import supervised_sweep
sweep = supervised_sweep.SWEEPS["cpu"]["fashion-mnist"]["sweep"]
data = load("fashion-mnist", seed=0)
start = time.perf_counter()
for setting in {settings}:
    supervised_sweep.run_one("sgb", setting, 0, data, sweep)
print(json.dumps({{"rate": {n} / (time.perf_counter() - start)}}))
"""
FIG2_SETTINGS = (10, 69, 387)  # hidden cell types: about 10x, 100x and 700x compression


def fig2_worker(settings: tuple[int, ...] = FIG2_SETTINGS) -> str:
    """Source of a worker that trains and evaluates Figure 2 SGB cells (Fashion-MNIST,
    ``cpu`` profile, seed 0) one after another and prints the cells per second."""
    return FIG2_WORKER.format(settings=tuple(settings), n=len(settings))


def ppo_worker(steps: int) -> str:
    """Source of a worker that prints the training env-steps/s of one Ant PPO run."""
    return PPO_WORKER.format(steps=steps)


def run_workers(source: str, n: int, pinned: bool) -> list[float]:
    """Start ``n`` workers running ``source`` at once; their reported rates."""
    procs = []
    for i in range(n):
        env = dict(os.environ)
        command = [sys.executable, "-c", source]
        if pinned:
            env["XLA_FLAGS"] = f"{env.get('XLA_FLAGS', '')} {ONE_THREAD}".strip()
            command = ["taskset", "-c", str(i % os.cpu_count()), *command]
        procs.append(subprocess.Popen(command, env=env, stdout=subprocess.PIPE, text=True))
    rates = []
    for proc in procs:
        out, _ = proc.communicate()
        if proc.returncode:
            raise RuntimeError(f"worker failed with exit code {proc.returncode}")
        rates.append(json.loads(out.strip().splitlines()[-1])["rate"])
    return rates


def compare(source: str, rounds: int) -> dict:
    """Alone and two-at-once, interleaved over ``rounds``; the median ratio of the rounds."""
    alone, pair, ratios = [], [], []
    for _ in range(rounds):
        single = run_workers(source, 1, pinned=False)[0]
        both = sum(run_workers(source, 2, pinned=True))
        alone.append(single)
        pair.append(both)
        ratios.append(both / single)
        print(f"alone {single:.0f}/s, two at once {both:.0f}/s, ratio {both / single:.2f}")
    return {"alone": alone, "two_at_once": pair, "ratios": ratios, "median_ratio": median(ratios)}


def median(values: list[float]) -> float:
    """The median of ``values``."""
    ordered = sorted(values)
    mid = len(ordered) // 2
    return ordered[mid] if len(ordered) % 2 else 0.5 * (ordered[mid - 1] + ordered[mid])


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--workloads", nargs="+", default=["ppo_ant", "fig2_cell"])
    parser.add_argument("--ppo-steps", type=int, default=400_000)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    workers = {"ppo_ant": lambda: ppo_worker(args.ppo_steps), "fig2_cell": fig2_worker}
    start = time.perf_counter()
    results = {name: compare(workers[name](), args.rounds) for name in args.workloads}
    print(json.dumps(results, indent=1))
    if args.out is not None:
        config = {"workloads": args.workloads, "ppo_steps": args.ppo_steps, "rounds": args.rounds}
        config["fig2_settings"] = list(FIG2_SETTINGS)
        record = provenance(config, "benchmark", [0], time.perf_counter() - start)
        print("wrote", write_results(args.out, results, record))


if __name__ == "__main__":
    main()
