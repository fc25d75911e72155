"""Figure 3: return against the number of cell types (SGB-PPO on Brax).

Trains vanilla PPO and SGB-PPO at several cell-type counts (hidden width 128) for several
seeds on one environment (the sweep: ``sgb.rl.sweep``); the innate return of the SGB
agents as a fraction of the vanilla agent's. Writes the checkpoint of every run
(``sgb.rl.runs``).
"""

from dataclasses import replace
from pathlib import Path

import numpy as np

from sgb.profiles import PROFILE_NAMES
from sgb.provenance import read_results
from sgb.recording import Recording, start
from sgb.rl.agent import NetworkConfig
from sgb.rl.ppo import PPOConfig
from sgb.rl.regimes import with_settings
from sgb.rl.runs import CHECKPOINT_DIR, checkpoint_name, finished_run, seed_sem, train_runs
from sgb.rl.sweep import BACKENDS, CellTypeSweep, sweep_config


def sweep_runs(config: CellTypeSweep) -> list[tuple[str, int | None, int]]:
    """(settings, cell types, seed) of every run, seed by seed: all points' seed 0, then
    seed 1, ..., so that a sweep stopped part way has every point at about the same
    number of seeds."""
    runs = [(p.settings, p.cell_types, seed) for p in config.points for seed in p.seeds]
    return sorted(runs, key=lambda run: run[2])


def run_fig3(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Train the sweep; write per-run returns, fractions of vanilla and checkpoints.

    Nothing is lost when the sweep dies: a run whose checkpoint exists with this
    profile's settings is not trained again (and keeps the provenance it was trained
    with), and a run in progress keeps its training state next to its checkpoint
    (``*.state.npz``) and continues from it. Several processes may run the same sweep at
    once: each trains the runs no other holds (``sgb.runlock``). After every run trained,
    the results file is written again from every finished checkpoint of the sweep
    (``"complete": false`` until all are).
    """
    if env not in BACKENDS:
        raise ValueError(f"env must be one of {sorted(BACKENDS)}, got {env!r}")
    recording = start(FIG3_PROFILES, profile, Path(out_dir) / "rl", f"fig3_{env}", choice=env)
    config = recording.config
    runs = [
        (
            f"fig3 {env} {settings} k={k} seed {seed}",
            run_config(config, settings, k),
            seed,
            Path(out_dir) / CHECKPOINT_DIR / checkpoint_name(env, k, seed, profile, settings),
        )
        for settings, k, seed in sweep_runs(config)
    ]
    return train_runs(runs, profile, lambda: write_sweep(recording, Path(out_dir)))


def run_config(config: CellTypeSweep, settings: str, cell_types: int | None) -> PPOConfig:
    """The PPO settings of the sweep's run at ``settings`` and ``cell_types``."""
    return with_settings(
        replace(config.ppo, network=NetworkConfig(cell_types=cell_types)), settings
    )


def write_sweep(recording: Recording, out_dir: Path) -> Path:
    """Write the results of every finished run of ``recording.config`` under ``out_dir``;
    the wall time recorded is the sum of the runs' own training times, whenever each was
    trained."""
    config = recording.config
    env = config.ppo.env.name
    runs = []
    for settings, k, seed in sweep_runs(config):
        name = checkpoint_name(env, k, seed, recording.profile, settings)
        record = finished_run(out_dir / CHECKPOINT_DIR / name, run_config(config, settings, k))
        if record is not None:
            runs.append({"settings": settings, "cell_types": k, "seed": seed, **record})
    results = {
        "env": env,
        "complete": len(runs) == len(sweep_runs(config)),
        "runs": runs,
        "summary": summarise_cell_types(runs),
        "summary_last_two": summarise_cell_types(runs, "last_two_return"),
    }
    return recording.write(results, sorted({r["seed"] for r in runs}), parts=runs)


def summarise_cell_types(runs: list[dict], score: str = "final_return") -> list[dict]:
    """Per settings and cell-type count: mean ``score`` (``"final_return"``, the last
    evaluation, or ``"last_two_return"``), SEM over seeds, fraction of vanilla and its SEM.

    The fraction divides each seed's return by the mean vanilla return.
    """
    vanilla = np.mean([r[score] for r in runs if r["cell_types"] is None])
    out = []
    for settings, k in dict.fromkeys((r["settings"], r["cell_types"]) for r in runs):
        values = np.array(
            [r[score] for r in runs if r["cell_types"] == k and r["settings"] == settings]
        )
        spread = seed_sem(values)
        out.append(
            {
                "settings": settings,
                "cell_types": k,
                "mean_return": float(values.mean()),
                "sem_return": spread,
                "fraction": float(values.mean() / vanilla),
                "sem_fraction": spread / abs(vanilla),
                "n_seeds": int(values.size),
            }
        )
    return out


def best_checkpoint(results_dir: Path, env: str = "ant") -> Path:
    """The SGB checkpoint with the highest final return in the cpu Figure 3 sweep of ``env``."""
    runs = read_results(Path(results_dir) / "rl" / f"fig3_{env}_cpu.json")["results"]["runs"]
    best = max((r for r in runs if r["cell_types"] is not None), key=lambda r: r["final_return"])
    return Path(results_dir) / CHECKPOINT_DIR / best["checkpoint"]


FIG3_PROFILES = {p: {env: sweep_config(env, p) for env in BACKENDS} for p in PROFILE_NAMES}
