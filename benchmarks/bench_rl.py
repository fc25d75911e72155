"""Benchmarks of sgb.rl on this machine, all ratios taken in one run.

1. Vanilla PPO of ``sgb.rl`` against ``brax.training.agents.ppo.train`` on the
   same environment, backend, step budget and hyperparameters (deterministic
   evaluation on ``eval_individuals`` episodes on both sides), over several
   seeds: final evaluation return and training env-steps/s.
2. SGB-PPO (64 cell types) against our vanilla PPO: env-steps/s and final return.
   The env-steps/s ratios come from the three trained side by side in one sitting:
   after each of Brax's training epochs, ours and SGB's train as many iterations, so
   each round's three rates meet the machine in the same state (medians of the
   per-round ratios; work on the machine during the long runs does not enter them).
3. Population evaluation: env-steps/s of 100 SGB individuals evaluated in one
   vmapped call, against stepping the bare environment with random actions at
   the same batch size.

Usage: ``python benchmarks/bench_rl.py [--steps 2000000] [--seeds 0 1 2]
[--out results/rl/bench_rl.json] [--max-runs N]``. Each finished run is kept in
``--partial`` with its commit and settings; with ``--max-runs`` the benchmark runs in
several sittings and the results file is written by the sitting that finishes it. A
kept run is reused only if its settings are today's and the code it ran (``sgb/`` for
ours, ``sgb/rl/envs.py`` for Brax's) is unchanged since its commit.
"""

import argparse
import functools
import json
import subprocess
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, replace
from pathlib import Path

import jax
import numpy as np
from brax.training.agents.ppo import networks as brax_networks
from brax.training.agents.ppo import train as brax_ppo

from sgb.provenance import atomic_write, git_commit, provenance
from sgb.recording import write_results
from sgb.rl.agent import NetworkConfig
from sgb.rl.envs import EnvSpec, make_env
from sgb.rl.population import population_returns
from sgb.rl.ppo import PPOConfig, init_state, train
from sgb.rl.trainer import make_trainer


def ours(config: PPOConfig, seed: int) -> dict:
    result = train(config, seed=seed)
    return {
        "final_return": result.eval_returns[-1],
        "train_steps_per_s": result.train_steps_per_s,
        "eval_returns": result.eval_returns,
        "wall_time_s": result.wall_time_s,
    }


def brax_reference(
    config: PPOConfig, seed: int, after_epoch: Callable[[int, dict], None] | None = None
) -> dict:
    """Brax's PPO with the same settings (one unroll per environment per update, as ours);
    ``after_epoch(step, metrics)``, if given, is called after each evaluation."""
    reports = []

    def progress(step: int, metrics: dict) -> None:
        reports.append((step, dict(metrics)))
        if after_epoch is not None:
            after_epoch(step, metrics)

    start = time.perf_counter()
    network_factory = functools.partial(
        brax_networks.make_ppo_networks,
        policy_hidden_layer_sizes=config.network.hidden,
        value_hidden_layer_sizes=config.network.hidden,
    )
    brax_ppo.train(
        environment=make_env(config.env),
        num_timesteps=config.total_steps,
        episode_length=config.episode_length,
        num_envs=config.num_envs,
        learning_rate=config.learning_rate,
        entropy_cost=config.entropy_coef,
        vf_loss_coefficient=config.value_coef,
        discounting=config.discount,
        gae_lambda=config.gae_lambda,
        clipping_epsilon=config.clip,
        unroll_length=config.unroll_length,
        batch_size=config.num_envs // config.num_minibatches,
        num_minibatches=config.num_minibatches,
        num_updates_per_batch=config.num_epochs,
        normalize_observations=True,
        reward_scaling=config.reward_scaling,
        num_evals=config.num_evals + 1,
        num_eval_envs=config.eval_individuals,
        deterministic_eval=True,
        network_factory=network_factory,
        seed=seed,
        progress_fn=progress,
    )
    final = reports[-1][1]
    return {
        "final_return": float(final["eval/episode_reward"]),
        "train_steps_per_s": float(final.get("training/sps", float("nan"))),
        "eval_returns": [float(m["eval/episode_reward"]) for _, m in reports],
        "wall_time_s": time.perf_counter() - start,
    }


def _chunk_rate(config: PPOConfig, iterations: int) -> Callable[[], float]:
    """A function that trains ``iterations`` more PPO iterations of one run of ``config``
    (seed 0, compiled beforehand) and returns their training env-steps/s."""
    step = make_trainer(config.step_settings()).iterations
    state = init_state(config, seed=0)
    for _ in range(2):  # compile and warm up, outside the timed rounds
        state, _ = step(state, iterations)
    jax.block_until_ready(state)

    def chunk() -> float:
        nonlocal state
        start = time.perf_counter()
        state, _ = step(state, iterations)
        jax.block_until_ready(state)
        return iterations * config.steps_per_iteration / (time.perf_counter() - start)

    return chunk


def training_throughput(
    config: PPOConfig, sgb_config: PPOConfig, rounds: int = 12, iterations: int = 20
) -> dict:
    """Training env-steps/s of Brax's PPO, our vanilla PPO and our SGB PPO, interleaved
    chunk by chunk: after each of Brax's training epochs (``iterations`` PPO iterations,
    timed by Brax itself, evaluation excluded) ours and SGB's train as many iterations,
    so the three share the machine's state of the moment. The first two rounds are
    dropped (Brax's training epoch compiles in both); the ratios are the medians of the
    per-round ratios."""
    ours_chunk = _chunk_rate(config, iterations)
    sgb_chunk = _chunk_rate(sgb_config, iterations)
    samples = []

    def after_epoch(step: int, metrics: dict) -> None:
        if "training/sps" in metrics:
            brax_sps = float(metrics["training/sps"])
            samples.append({"brax": brax_sps, "ours": ours_chunk(), "sgb_64_types": sgb_chunk()})

    steps = rounds * iterations * config.steps_per_iteration
    brax_reference(replace(config, total_steps=steps, num_evals=rounds), 0, after_epoch)
    kept = samples[2:]
    sps = {name: float(np.median([r[name] for r in kept])) for name in kept[0]}
    return {
        "steps_per_round": iterations * config.steps_per_iteration,
        "rounds": kept,
        "steps_per_s": sps,
        "ratio_ours_to_brax": float(np.median([r["ours"] / r["brax"] for r in kept])),
        "ratio_sgb_to_ours": float(np.median([r["sgb_64_types"] / r["ours"] for r in kept])),
    }


def population_throughput(n: int = 100, episode_length: int = 1000) -> dict:
    """Env-steps/s: n individuals in one vmapped call vs n bare envs with random actions."""
    spec = EnvSpec("ant", "spring")
    config = PPOConfig(env=spec, network=NetworkConfig(cell_types=64))
    ts = init_state(config, seed=0)
    args = (spec, config.network, ts.params.actor, ts.normalizer, n, 1, episode_length)
    population_returns(*args, seed=0)  # compile
    t0 = time.perf_counter()
    population_returns(*args, seed=1)
    population_s = time.perf_counter() - t0

    env = make_env(spec)

    @jax.jit
    def random_rollout(key):
        state = jax.vmap(env.reset)(jax.random.split(key, n))

        def step(state, k):
            action = jax.random.uniform(k, (n, env.action_size), minval=-1.0, maxval=1.0)
            return jax.vmap(env.step)(state, action), None

        state, _ = jax.lax.scan(step, state, jax.random.split(key, episode_length))
        return state.reward

    jax.block_until_ready(random_rollout(jax.random.PRNGKey(0)))
    t0 = time.perf_counter()
    jax.block_until_ready(random_rollout(jax.random.PRNGKey(1)))
    bare_s = time.perf_counter() - t0
    steps = n * episode_length
    return {
        "batch": n,
        "episode_length": episode_length,
        "population_steps_per_s": steps / population_s,
        "bare_env_steps_per_s": steps / bare_s,
        "ratio": bare_s / population_s,
    }


def _mean(runs: list[dict], key: str) -> float:
    return float(np.mean([run[key] for run in runs]))


def _load(path: Path) -> dict:
    return json.loads(path.read_text()) if path.exists() else {}


CODE_OF = {
    "brax": ["sgb/rl/envs.py"],
    "ours": ["sgb"],
    "sgb_64_types": ["sgb"],
    "throughput": ["sgb"],
    "training_throughput": ["sgb"],
}


def _still_valid(run: dict, name: str, settings: dict) -> bool:
    """Whether a kept run used today's settings and code (committed, unchanged since)."""
    commit = run.get("git_commit", "")
    if run.get("settings") != settings or commit.endswith("+dirty") or commit == "unknown":
        return False
    root = Path(__file__).resolve().parent.parent
    diff = ["git", "diff", "--quiet", commit, "HEAD", "--", *CODE_OF[name]]
    return subprocess.run(diff, cwd=root).returncode == 0


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=2_000_000)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--sgb-seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--out", type=Path, default=Path("results/rl/bench_rl.json"))
    parser.add_argument(
        "--partial",
        type=Path,
        default=Path(tempfile.gettempdir()) / "sgb_bench_rl.partial.json",
        help="runs finished so far; a rerun resumes from them (same code and settings)",
    )
    parser.add_argument("--max-runs", type=int, default=None, help="stop after this many runs")
    args = parser.parse_args()
    config = PPOConfig(env=EnvSpec("ant", "spring"), total_steps=args.steps, num_evals=4)
    sgb_config = replace(config, network=NetworkConfig(cell_types=64))
    done = _load(args.partial)
    commit = git_commit()  # the code this process runs, whatever is committed meanwhile
    settings = {"ours": asdict(config), "sgb_64_types": asdict(sgb_config)}
    # the speed ratios first, so that a sitting split with --max-runs can take them idle
    plan = [("training_throughput", None, lambda _: training_throughput(config, sgb_config))]
    plan += [("throughput", None, lambda _: population_throughput())]
    plan += [("brax", seed, lambda seed: brax_reference(config, seed)) for seed in args.seeds]
    plan += [("ours", seed, lambda seed: ours(config, seed)) for seed in args.seeds]
    plan += [("sgb_64_types", seed, lambda seed: ours(sgb_config, seed)) for seed in args.sgb_seeds]
    ran, keys = 0, []
    for name, seed, run in plan:
        key = name if seed is None else f"{name}/{seed}"
        keys.append(key)
        wanted = json.loads(json.dumps(settings.get(name, settings["ours"])))
        if key in done and _still_valid(done[key], name, wanted):
            continue
        if args.max_runs is not None and ran >= args.max_runs:
            print("stopped; rerun to resume from", args.partial)
            return
        start = time.perf_counter()
        done[key] = {
            "seed": seed,
            **run(seed),
            "bench_wall_time_s": time.perf_counter() - start,
            "git_commit": commit,
            "settings": wanted,
        }
        print(key, done[key])
        atomic_write(args.partial, json.dumps(done).encode())
        ran += 1
    results = {
        "throughput": done["throughput"],
        "training_throughput": done["training_throughput"],
        "sgb_network": asdict(sgb_config.network),
    }
    for name, seeds in (
        ("ours", args.seeds),
        ("brax", args.seeds),
        ("sgb_64_types", args.sgb_seeds),
    ):
        results[name] = [done[f"{name}/{seed}"] for seed in seeds]
        results[f"{name}_mean_final_return"] = _mean(results[name], "final_return")
        results[f"{name}_mean_steps_per_s"] = _mean(results[name], "train_steps_per_s")
    results["return_ratio_ours_to_brax"] = (
        results["ours_mean_final_return"] / results["brax_mean_final_return"]
    )
    results["sps_ratio_ours_to_brax"] = done["training_throughput"]["ratio_ours_to_brax"]
    results["sps_ratio_sgb_to_ours"] = done["training_throughput"]["ratio_sgb_to_ours"]
    print({k: v for k, v in results.items() if not isinstance(v, list | dict)})
    runs = [done[key] for key in keys]
    wall = sum(run["bench_wall_time_s"] for run in runs)
    record = provenance(config, "benchmark", args.seeds, wall)
    record["run_commits"] = sorted({run["git_commit"] for run in runs})
    print("wrote", write_results(args.out, results, record))


if __name__ == "__main__":
    main()
