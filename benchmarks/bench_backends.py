"""Which Brax backend trains the HalfCheetah fastest on this machine, and what a vanilla
PPO run on it reaches within a ``cpu``-sized budget.

1. For each backend, a short vanilla PPO run with the HalfCheetah ``cpu`` settings of
   Figure 3: training env-steps/s (after the compiling chunk) and the wall time with
   compilation. The runs go back to back in one sitting, so the ratios are fair.
2. With the fastest backend, vanilla PPO for ``--reach-steps`` env steps: its learning
   curve (deterministic evaluation returns).

Usage: ``python benchmarks/bench_backends.py [--steps 200000] [--reach-steps 2000000]
[--out results/rl/bench_backends.json]``.
"""

import argparse
import time
from dataclasses import replace
from pathlib import Path

from sgb.provenance import provenance
from sgb.recording import write_results
from sgb.rl.ppo import PPOConfig, train
from sgb.rl.sweep import sweep_config

BACKENDS = ("spring", "positional", "generalized", "mjx")


def backend_throughput(config: PPOConfig, backend: str, steps: int) -> dict:
    """Training env-steps/s and wall time (s, compilation included) of ``steps`` env steps."""
    result = train(replace(config, env=replace(config.env, backend=backend), total_steps=steps))
    return {"train_steps_per_s": result.train_steps_per_s, "wall_time_s": result.wall_time_s}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--reach-steps", type=int, default=2_000_000)
    parser.add_argument("--backends", nargs="+", default=list(BACKENDS), choices=BACKENDS)
    parser.add_argument("--out", type=Path, default=Path("results/rl/bench_backends.json"))
    args = parser.parse_args()
    config = replace(sweep_config("halfcheetah", "cpu").ppo, num_evals=2)
    start = time.perf_counter()
    speeds = {}
    for backend in args.backends:
        speeds[backend] = backend_throughput(config, backend, args.steps)
        print(backend, speeds[backend], flush=True)
    fastest = max(speeds, key=lambda b: speeds[b]["train_steps_per_s"])
    reach_config = replace(
        config,
        env=replace(config.env, backend=fastest),
        total_steps=args.reach_steps,
        num_evals=8,
    )
    reach = train(reach_config, seed=0)
    results = {
        "env": config.env.name,
        "throughput_steps": args.steps,
        "throughput": speeds,
        "fastest": fastest,
        "reach": {
            "backend": fastest,
            "eval_steps": reach.eval_steps,
            "eval_returns": reach.eval_returns,
            "train_steps_per_s": reach.train_steps_per_s,
            "wall_time_s": reach.wall_time_s,
        },
    }
    print(results)
    record = provenance(reach_config, "benchmark", [0], time.perf_counter() - start)
    print("wrote", write_results(args.out, results, record))


if __name__ == "__main__":
    main()
