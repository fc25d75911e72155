"""The Ant under the authors' own training regime at the paper's budget of 5 x 10^7 steps.

Vanilla PPO and the authors' genome at 64 types first (seed 0, then more seeds), then 128
and 16 types (seed 0): every run of ``sgb.rl.regimes.authors_regime``, the SGB runs with
the authors' genome (``sgb.rl.regimes.with_settings(..., "authors")``). The vanilla
network has the SGB's width, 128 (their ``ant_vanilla.yaml`` has 64 and 10^8 steps), so
that the comparison isolates the bottleneck at one budget. Each run is evaluated as the
authors evaluate (``sgb.rl.trainer.Trainer.window_return``), and its return is also
given on their Figure 3 scale (``sgb.rl.regimes.authors_scale``).

Runs are resumable and shared between processes as Figure 3's are
(``sgb.experiments.rl.trained_run``, ``sgb.runlock``); after every run the results file
is written again from every finished checkpoint (``"complete": false`` until all are).
"""

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from sgb import runlock, validation
from sgb.experiments import PROFILE_NAMES, check_profile
from sgb.experiments.rl import (
    CHECKPOINT_DIR,
    finished_run,
    ppo_settings,
    seed_sem,
    trained_run,
)
from sgb.recording import Recording, start
from sgb.rl.agent import NetworkConfig
from sgb.rl.ppo import PPOConfig
from sgb.rl.regimes import authors_regime, authors_scale, with_settings


@dataclass(frozen=True)
class RegimeRuns:
    """The runs, (cell types or None for vanilla, seed) in the order they train, and the
    PPO settings they share before ``run_config`` makes each one."""

    runs: tuple[tuple[int | None, int], ...]
    ppo: PPOConfig

    def __post_init__(self) -> None:
        for k, seed in self.runs:
            validation.seed("seed", seed)
            if k is not None:
                validation.integer("cell types", k)


def regime_config(profile: str) -> RegimeRuns:
    """The runs at ``profile``: at ``cpu`` and ``paper`` vanilla and 64 types at seed 0,
    then 128 and 16 types at seed 0, then vanilla and 64 types at seeds 1 and 2.
    Evaluations: 256 environments at ``cpu`` (the authors' 2048 cost 2 x 10^6 steps each,
    40 % of the training), 2048 at ``paper``; smoke is a few hundred steps."""
    check_profile(profile)
    base = authors_regime(ppo_settings("ant", "cpu"))
    if profile == "smoke":
        ppo = replace(
            base,
            total_steps=2 * 16 * 5 * 2,
            num_envs=16,
            unrolls_per_iteration=2,
            num_minibatches=4,
            num_epochs=1,
            num_evals=2,
            eval_individuals=4,
            episode_length=64,
        )
        return RegimeRuns(((None, 0), (16, 0)), ppo)
    runs = ((None, 0), (64, 0), (128, 0), (16, 0), (None, 1), (64, 1), (None, 2), (64, 2))
    return RegimeRuns(runs, replace(base, eval_individuals=256 if profile == "cpu" else 2048))


def run_config(config: RegimeRuns, cell_types: int | None) -> PPOConfig:
    """The settings of the run at ``cell_types``: the authors' genome for an SGB."""
    network = NetworkConfig(cell_types=cell_types, bayesian_biases=cell_types is not None)
    ppo = replace(config.ppo, network=network)
    return ppo if cell_types is None else with_settings(ppo, "authors")


def checkpoint_name(cell_types: int | None, seed: int, profile: str) -> str:
    label = "vanilla" if cell_types is None else f"k{cell_types}"
    return f"ant_regime_{label}_s{seed}_{profile}.msgpack"


def run(profile: str, out_dir: Path) -> Path:
    """Train every run not yet trained (each one resumable), writing the results file
    after each."""
    recording = start(PROFILES, profile, Path(out_dir) / "rl", "regime_ant")
    config = recording.config
    for i, (k, seed) in enumerate(config.runs):
        label = f"regime ant k={k} seed {seed} ({i + 1}/{len(config.runs)})"
        checkpoint = Path(out_dir) / CHECKPOINT_DIR / checkpoint_name(k, seed, profile)
        with runlock.claim(checkpoint) as mine:
            if not mine:
                print(f"{label}: another process is training it", flush=True)
                continue
            if trained_run(run_config(config, k), seed, checkpoint, profile, label):
                write_regime(recording, Path(out_dir))
    return write_regime(recording, Path(out_dir))


def write_regime(recording: Recording, out_dir: Path) -> Path:
    """Write every finished run of ``recording.config`` under ``out_dir``: its learning
    curve, its final return on both scales, and per cell-type count the mean over seeds
    with each seed's fraction of the vanilla run of the same seed."""
    config = recording.config
    runs = []
    for k, seed in config.runs:
        checkpoint = out_dir / CHECKPOINT_DIR / checkpoint_name(k, seed, recording.profile)
        record = finished_run(checkpoint, run_config(config, k))
        if record is not None:
            scaled = authors_scale("ant", record["final_return"])
            runs.append({"cell_types": k, "seed": seed, "authors_scale": scaled, **record})
    results = {
        "env": "ant",
        "complete": len(runs) == len(config.runs),
        "runs": runs,
        "summary": summarise_regime(runs),
    }
    return recording.write(results, sorted({r["seed"] for r in runs}), parts=runs)


def summarise_regime(runs: list[dict]) -> list[dict]:
    """Per cell-type count (vanilla first): seeds, mean final return and SEM, mean on the
    authors' scale, and the fraction of vanilla over the seeds that have a vanilla run."""
    vanilla = {r["seed"]: r["final_return"] for r in runs if r["cell_types"] is None}
    out = []
    for k in dict.fromkeys(r["cell_types"] for r in runs):
        mine = [r for r in runs if r["cell_types"] == k]
        returns = np.array([r["final_return"] for r in mine])
        paired = [r["final_return"] / vanilla[r["seed"]] for r in mine if r["seed"] in vanilla]
        out.append(
            {
                "cell_types": k,
                "seeds": [r["seed"] for r in mine],
                "mean_return": float(returns.mean()),
                "sem_return": seed_sem(returns),
                "mean_authors_scale": float(np.mean([r["authors_scale"] for r in mine])),
                "fraction_of_vanilla": float(np.mean(paired)) if paired else None,
            }
        )
    return out


PROFILES = {p: regime_config(p) for p in PROFILE_NAMES}
