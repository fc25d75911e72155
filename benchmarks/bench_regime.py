"""Where the time of the authors' regime goes: each phase of a training iteration against
the bare simulator, on one pinned core with one XLA thread.

At the regime's settings on the Ant (2048 environments, 32 unrolls of 5 steps an
iteration, 4 epochs x 32 minibatches; ``sgb.rl.regimes.authors_regime``), for vanilla and
for the authors' genome at 64 types, in interleaved rounds (one call of each phase a
round, after a compiling call):

- ``simulator``: the bare Brax Ant (``spring``) stepping every environment for an
  iteration's steps with a fixed random policy (a linear map of the observation drawn once);
- ``collection``: the regime's unrolls alone (``Trainer.collect``), no update;
- ``update``: the 4 x 32 minibatch steps alone (``Trainer.sgd``) on a stored batch;
- ``iteration``: whole iterations (``Trainer.iterations``: collection, normaliser, update);
- ``evaluation``: the last of the authors' evaluations (``Trainer.window_return`` on
  2048 environments for 1000 steps), and ``interim evaluation``, one of those before it
  (on 256, ``PPOConfig.eval_size``), counted apart; a run makes ``num_evals + 1``, the
  last one large; ``run_hours`` are a run's training and evaluations at these rates, and
  ``evaluation_share`` the evaluations' part of the two;
- where the update's time goes, over the same 4 x 32 minibatches of the stored batch:
  ``loss forward`` (the PPO loss alone, ``sgb.rl.losses.ppo_loss``) and ``loss
  gradients`` (its gradient, no optimiser step); ``update_shares`` splits the update
  into the forward pass, the backward pass (gradients less forward) and the optimiser
  (update less gradients).

Each phase is printed as env-steps/s (the environment steps an iteration trains on, per
second) and as a ratio to the simulator's; the bound is collection and update measured
apart, 1 / (1/collection + 1/update). The SGD's floating-point work per env step is
XLA's cost analysis of one minibatch's loss gradient times the epochs x minibatches (the
cost analysis of the whole update counts its loop body once); ``update_gflops`` is that
work at the update's measured rate, beside ``matmul_gflops``, the core's rate on a plain
float32 matrix product of the minibatch's shape (rows x 128 by 128 x 128, 64 in a chain),
about the most the update's dense layers could reach.

Usage: ``python benchmarks/bench_regime.py [--core 0] [--rounds 2] [--iterations 2]
[--out results/rl/bench_regime.json]`` (written with provenance). The process pins itself.
"""

import argparse
import os
import statistics
import sys
import time

ONE_THREAD = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"


def _pin(core: int) -> None:
    """This process on ``core`` with one XLA thread; before JAX is imported."""
    if "jax" in sys.modules:
        raise RuntimeError("pin before importing jax")
    os.sched_setaffinity(0, {core})
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {ONE_THREAD}".strip()


def _timed(fn, *args) -> float:
    """Seconds of one call of ``fn(*args)``, its outputs ready."""
    import jax

    start = time.perf_counter()
    jax.block_until_ready(fn(*args))
    return time.perf_counter() - start


def phases(cell_types: int | None, iterations: int) -> dict:
    """The phases of one configuration, each a ``(function, args, env_steps)``, and the
    SGD's flops per env step."""
    import jax

    from sgb.rl.losses import ppo_loss
    from sgb.rl.ppo import init_state
    from sgb.rl.regime_runs import RUNS, RegimeRun, run_config
    from sgb.rl.trainer import make_trainer

    config = run_config(RUNS["cpu"], RegimeRun(cell_types, 0))
    trainer = make_trainer(config.step_settings())
    ts = trainer.restart_all(init_state(config, seed=0))
    steps = config.steps_per_iteration
    env = trainer.env
    t = config.unroll_length * config.unrolls_per_iteration
    mix = jax.random.normal(jax.random.PRNGKey(1), (env.observation_size, env.action_size))

    @jax.jit
    def simulate(state):
        def step(state, _):
            return jax.vmap(env.step)(state, jax.numpy.tanh(state.obs @ mix)), None

        return jax.lax.scan(step, state, None, t)[0]

    collect = jax.jit(trainer.collect)
    _, data = collect(ts)
    sgd = jax.jit(trainer.sgd)
    rows = config.num_envs * config.unrolls_per_iteration // config.num_minibatches
    minibatch = jax.tree_util.tree_map(lambda x: x[:rows], data)
    grad = jax.jit(
        jax.grad(
            lambda p: ppo_loss(
                p, minibatch, ts.normalizer, ts.key, trainer.agent, config.step_settings().loss
            )[0]
        )
    )
    flops = _flops(grad, ts.params) * config.num_epochs * config.num_minibatches
    a = jax.random.normal(jax.random.PRNGKey(3), (rows, 128))
    b = jax.random.normal(jax.random.PRNGKey(4), (128, 128))
    matmul = jax.jit(lambda a, b: jax.lax.fori_loop(0, 64, lambda _, x: jax.numpy.tanh(x @ b), a))
    settings = config.step_settings()

    def evaluation(size: int) -> tuple:
        def window(ts):
            return trainer.window_return(ts.params, ts.normalizer, jax.random.PRNGKey(2), size)

        return window, (ts,), size * config.episode_length

    def loss(params, batch, key):
        return ppo_loss(params, batch, ts.normalizer, key, trainer.agent, settings.loss)[0]

    return {
        "loss forward": (_minibatches(loss, settings), (ts.params, data, ts.key), steps),
        "loss gradients": (
            _minibatches(jax.grad(loss), settings),
            (ts.params, data, ts.key),
            steps,
        ),
        "simulator": (simulate, (ts.env_state,), steps),
        "collection": (collect, (ts,), steps),
        "update": (sgd, (ts, data), steps),
        "iteration": (lambda ts: trainer.iterations(ts, iterations), (ts,), iterations * steps),
        "evaluation": evaluation(config.eval_size(last=True)),
        "interim evaluation": evaluation(config.eval_size(last=False)),
        "matmul": (matmul, (a, b), 64 * 2 * rows * 128 * 128),
        "sgd_flops_per_env_step": flops / steps,
        "evals_per_run": config.num_evals + int(config.eval_at_start),
        "iterations_per_run": config.iterations // config.num_evals * config.num_evals,
        "steps_per_iteration": steps,
    }


def _minibatches(step, settings):
    """Jitted ``(params, data, key) -> sum``: ``step(params, minibatch, key)`` on every
    minibatch of the update's epochs (the same shapes and gathers as ``Trainer.sgd``,
    the parameters held fixed), its outputs summed so that none is left out."""
    import jax
    import jax.numpy as jnp

    s = settings
    samples = s.num_envs * s.unrolls_per_iteration
    count = s.num_epochs * s.num_minibatches

    def run(params, data, key):
        def minibatch(total, xs):
            idx, k = xs
            batch = jax.tree_util.tree_map(lambda x: x[idx], data)
            leaves = jax.tree_util.tree_leaves(step(params, batch, k))
            return total + sum(jnp.sum(leaf) for leaf in leaves), None

        perms = jax.vmap(lambda k: jax.random.permutation(k, samples))(
            jax.random.split(key, s.num_epochs)
        )
        xs = (perms.reshape(count, -1), jax.random.split(key, count))
        return jax.lax.scan(minibatch, 0.0, xs)[0]

    return jax.jit(run)


def _flops(fn, *args) -> float:
    """XLA's count of the floating-point operations of one call of jitted ``fn``."""
    cost = fn.lower(*args).compile().cost_analysis()
    return (cost[0] if isinstance(cost, list) else cost)["flops"]


def measure(cell_types: int | None, rounds: int, iterations: int) -> dict:
    """Median env-steps/s of every phase over ``rounds`` interleaved rounds, their ratios
    to the simulator, the bound and the share of a run's time its evaluations take."""
    measured = phases(cell_types, iterations)
    names = ("simulator", "collection", "update", "iteration", "evaluation")
    names += ("interim evaluation", "matmul")
    names += ("loss forward", "loss gradients")
    for name in names:  # compile
        fn, args, _ = measured[name]
        _timed(fn, *args)
    seconds = {name: [] for name in names}
    for _ in range(rounds):
        for name in names:
            fn, args, _ = measured[name]
            seconds[name].append(_timed(fn, *args))
    rate = {n: measured[n][2] / statistics.median(seconds[n]) for n in names}
    matmul_gflops = rate.pop("matmul") / 1e9
    names = tuple(n for n in names if n != "matmul")
    update, forward, gradients = (
        statistics.median(seconds[n]) for n in ("update", "loss forward", "loss gradients")
    )
    shares = {
        "forward": forward / update,
        "backward": (gradients - forward) / update,
        "optimizer": (update - gradients) / update,
    }
    bound = 1.0 / (1.0 / rate["collection"] + 1.0 / rate["update"])
    train_s = measured["iterations_per_run"] * measured["steps_per_iteration"] / rate["iteration"]
    interim = measured["evals_per_run"] - 1
    eval_s = sum(
        count * measured[name][2] / rate[name]
        for name, count in (("evaluation", 1), ("interim evaluation", interim))
    )
    return {
        "cell_types": cell_types,
        "env_steps_per_s": rate,
        "ratio_to_simulator": {n: rate[n] / rate["simulator"] for n in names},
        "seconds": seconds,
        "bound_env_steps_per_s": bound,
        "iteration_over_bound": rate["iteration"] / bound,
        "bound_over_simulator": bound / rate["simulator"],
        "sgd_flops_per_env_step": measured["sgd_flops_per_env_step"],
        "update_gflops": measured["sgd_flops_per_env_step"] * rate["update"] / 1e9,
        "matmul_gflops": matmul_gflops,
        "run_hours": {"training": train_s / 3600, "evaluations": eval_s / 3600},
        "evaluation_share": eval_s / (train_s + eval_s),
        "update_shares": shares,
    }


def table(rows: list[dict]) -> str:
    """The results as a text table: env-steps/s and the ratio to the simulator."""
    lines = [f"{'phase':<22}" + "".join(f"{_name(r):>24}" for r in rows)]
    phases = ("simulator", "collection", "update", "iteration", "evaluation")
    for phase in (*phases, "interim evaluation", "loss forward", "loss gradients"):
        cells = [
            f"{r['env_steps_per_s'][phase]:>14,.0f} ({r['ratio_to_simulator'][phase]:.2f}x)"
            for r in rows
        ]
        lines.append(f"{phase:<22}" + "".join(f"{c:>24}" for c in cells))
    lines.append(
        f"{'bound':<22}"
        + "".join(
            f"{r['bound_env_steps_per_s']:>14,.0f} ({r['bound_over_simulator']:.2f}x)" for r in rows
        )
    )
    formats = {"iteration_over_bound": "{:.3f}", "sgd_flops_per_env_step": "{:,.0f}"}
    formats |= {"update_gflops": "{:.1f}", "matmul_gflops": "{:.1f}"}
    for key, fmt in formats.items():
        lines.append(f"{key:<22}" + "".join(f"{fmt.format(r[key]):>24}" for r in rows))
    for part in ("training", "evaluations"):
        hours = "".join(f"{r['run_hours'][part]:>23.2f}h" for r in rows)
        lines.append(f"{'run ' + part:<22}" + hours)
    shares = "".join(f"{r['evaluation_share']:>24.1%}" for r in rows)
    lines.append(f"{'evaluation share':<22}" + shares)
    for part in ("forward", "backward", "optimizer"):
        shares = "".join(f"{r['update_shares'][part]:>24.2f}" for r in rows)
        lines.append(f"{'update ' + part:<22}" + shares)
    return "\n".join(lines)


def _name(row: dict) -> str:
    return "vanilla" if row["cell_types"] is None else f"{row['cell_types']} types"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--core", type=int, default=0)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--iterations", type=int, default=2)
    parser.add_argument("--out", default="results/rl/bench_regime.json")
    args = parser.parse_args()
    _pin(args.core)
    start = time.perf_counter()
    rows = [measure(k, args.rounds, args.iterations) for k in (None, 64)]
    print(table(rows))
    from sgb.provenance import provenance
    from sgb.recording import write_results

    record = provenance(vars(args), "cpu", [0], time.perf_counter() - start)
    write_results(args.out, {"rows": rows, "table": table(rows).splitlines()}, record)


if __name__ == "__main__":
    main()
