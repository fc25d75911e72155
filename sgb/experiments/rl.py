"""Figures 3, 4 and 5: SGB-PPO on Brax, cell-type sweeps, population diversity, mean network.

- ``fig3``: train vanilla PPO and SGB-PPO at several cell-type counts (hidden
  width 128) for several seeds on one environment; innate return of the
  SGB agents as a fraction of the vanilla agent's. Writes checkpoints of
  every run.
- ``fig4``: sample N individuals from a trained SGB (a checkpoint) and
  evaluate each for several episodes on the Ant with normal and long legs
  (4E) and on two physical niches (4F); Pearson r between conditions.
- ``fig5``: the same individuals against the mean network on the normal Ant,
  on the same initial states; paired t-test.
"""

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from sgb import runlock, stats, validation
from sgb.paths import committed_results
from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.provenance import provenance, read_results
from sgb.recording import Recording, start
from sgb.rl import checkpoints
from sgb.rl.agent import NetworkConfig
from sgb.rl.envs import EnvSpec
from sgb.rl.ppo import PPOConfig, train
from sgb.rl.protocols import (
    PopulationConfig,
    authors_protocol,
    compare,
    individuals_vs_mean,
    load_agent,
    population_on,
)
from sgb.rl.regimes import ABLATIONS, SETTINGS, with_settings

CHECKPOINT_DIR = Path("rl") / "checkpoints"
BACKENDS = {"ant": "spring", "halfcheetah": "spring"}


@dataclass(frozen=True)
class SweepPoint:
    """One point of Figure 3: genome settings, cell types (None = vanilla), its seeds."""

    settings: str
    cell_types: int | None
    seeds: tuple[int, ...]

    def __post_init__(self) -> None:
        validation.choice("settings", self.settings, SETTINGS + ABLATIONS)
        validation.integers("seeds", self.seeds, minimum=0)


@dataclass(frozen=True)
class CellTypeSweep:
    """Figure 3: the points of the sweep and the PPO settings they share."""

    points: tuple[SweepPoint, ...]
    ppo: PPOConfig

    @property
    def cell_types(self) -> tuple[int | None, ...]:
        """The cell-type counts of the sweep, in order of first appearance."""
        return tuple(dict.fromkeys(p.cell_types for p in self.points))

    @property
    def seeds(self) -> tuple[int, ...]:
        """Every seed any point runs, ascending."""
        return tuple(sorted({seed for p in self.points for seed in p.seeds}))


def ppo_settings(env: str, profile: str) -> PPOConfig:
    """PPO settings per profile; the paper's: 2048 envs, 50M steps. The clip is 0.3, what
    the authors' code hard-codes (``self.epsilon = 0.3`` in ``BayesianAgent``); the paper's
    Table 2 gives 0.001 for the Ant. The entropy weight is Table 2's (1e-2 Ant, 1e-3
    HalfCheetah)."""
    spec = EnvSpec(env, BACKENDS[env])
    clip, entropy = (0.3, 1e-2) if env == "ant" else (0.3, 1e-3)
    base = PPOConfig(env=spec, clip=clip, entropy_coef=entropy)
    if profile == "smoke":
        return replace(
            base, total_steps=4096, num_envs=32, episode_length=64, num_evals=1, eval_individuals=4
        )
    if profile == "cpu":  # long enough that vanilla PPO walks and runs (bench_rl, bench_backends)
        return replace(base, total_steps=2_000_000, num_evals=4, eval_individuals=32)
    return replace(
        base,
        total_steps=50_000_000,
        num_envs=2048,
        unroll_length=5,
        num_minibatches=32,
        num_evals=10,
        eval_individuals=128,
    )


def sweep_config(env: str, profile: str) -> CellTypeSweep:
    """The Figure 3 sweep for ``env`` at ``profile``.

    At ``cpu`` on the Ant, the points the verdicts compare (vanilla, 128 and 16 types)
    get 10 seeds and the others 5: with the seed spread of the first 3 seeds (SD of the
    fraction of vanilla about 0.2-0.3), that is what a difference of 0.3 of vanilla
    between 128 and 16 types needs at 80 % power (chapter 5 computes the power reached).
    The typing ablation runs at 16 types with 5 seeds.
    """
    check_profile(profile)
    if env not in BACKENDS:
        raise ValueError(f"env must be one of {sorted(BACKENDS)}, got {env!r}")
    if profile == "smoke":
        many = few = (0,)
        types, ablations = (None, 16), ()
    elif profile == "cpu" and env == "ant":
        many, few = tuple(range(10)), tuple(range(5))
        types, ablations = (None, 128, 64, 32, 16), ABLATIONS
    elif profile == "cpu":
        many, few = tuple(range(5)), tuple(range(3))
        types, ablations = (None, 128, 64, 32, 16), ()
    else:
        many = few = tuple(range(5))
        types, ablations = (None, 128, 64, 48, 32, 16), ()
    compared = (None, types[1], types[-1])
    points = [SweepPoint("ours", None, many)]
    points += [
        SweepPoint(settings, k, many if k in compared else few)
        for settings in SETTINGS
        for k in types
        if k is not None
    ]
    points += [SweepPoint(name, types[-1], few) for name in ablations]
    return CellTypeSweep(tuple(points), ppo_settings(env, profile))


def checkpoint_name(
    env: str,
    cell_types: int | None,
    seed: int,
    profile: str,
    settings: str = "ours",
    rho_init: float = NetworkConfig.rho_init,
) -> str:
    """File name of one run's checkpoint (Figure 3; ``rho_init``: the spread sweep)."""
    label = "vanilla" if cell_types is None else f"k{cell_types}"
    if settings != "ours":
        label += f"_{settings}"
    if rho_init != NetworkConfig.rho_init:
        label += f"_rho{rho_init:g}"
    return f"{env}_{label}_s{seed}_{profile}.msgpack"


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
    planned = sweep_runs(config)
    for i, (settings, k, seed) in enumerate(planned):
        label = f"fig3 {env} {settings} k={k} seed {seed} ({i + 1}/{len(planned)})"
        checkpoint = (
            Path(out_dir) / CHECKPOINT_DIR / checkpoint_name(env, k, seed, profile, settings)
        )
        with runlock.claim(checkpoint) as mine:
            if not mine:
                print(f"{label}: another process is training it", flush=True)
                continue
            if trained_run(run_config(config, settings, k), seed, checkpoint, profile, label):
                write_sweep(recording, Path(out_dir))
    return write_sweep(recording, Path(out_dir))


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


def trained_run(ppo: PPOConfig, seed: int, checkpoint: Path, profile: str, label: str) -> bool:
    """Make sure ``checkpoint`` holds ``ppo`` trained with ``seed``: train it unless it
    does (a killed run continues from its training state, ``*.state.npz``, kept beside
    it); returns whether it trained now. ``label`` names the run in what it prints."""
    if finished_run(checkpoint, ppo) is not None:
        print(f"{label}: reused {checkpoint}", flush=True)
        return False
    state_file = checkpoint.with_suffix(".state.npz")
    print(f"{label}: {'resumed' if state_file.exists() else 'training'}", flush=True)
    result = train(ppo, seed=seed, state_file=state_file, label=label)
    checkpoints.save(checkpoint, result, provenance(ppo, profile, [seed], result.wall_time_s))
    state_file.unlink()
    return True


def finished_run(checkpoint: Path, ppo: PPOConfig) -> dict | None:
    """The record kept in ``checkpoint`` if it holds a run trained with ``ppo`` (``None``
    if there is none, or it was trained with other settings; its intermediate evaluations
    may have had another size, ``PPOConfig.trains_as``): its learning curve, its
    scores (the last evaluation; the mean of the last two), its speed, wall time and
    the commit and date it was trained at. A damaged checkpoint counts as none (it is said
    so), so that the sweep trains the run again."""
    if not checkpoint.exists():
        return None
    try:
        config, _, _, meta = checkpoints.load(checkpoint)
    except validation.CorruptFile as error:
        print(f"{error}: it is trained again", flush=True)
        return None
    if not config.trains_as(ppo):
        return None
    returns = meta["eval_returns"]
    trained = meta.get("provenance", {})
    return {
        "final_return": returns[-1],
        "last_two_return": float(np.mean(returns[-2:])),
        **{key: meta[key] for key in ("eval_steps", "eval_returns", "train_steps_per_s")},
        "wall_time_s": meta["wall_time_s"],
        "git_commit": trained.get("git_commit", "not recorded"),
        "date": trained.get("date", "not recorded"),
        "checkpoint": checkpoint.name,
    }


def seed_sem(values: np.ndarray) -> float:
    """SEM over seeds of a 1-D array; NaN for a single seed."""
    return float(stats.sem(values)) if values.size > 1 else float("nan")


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


def population_config(profile: str) -> PopulationConfig:
    """Figures 4 and 5 settings: the committed cpu checkpoint of the Ant with 64 cell types."""
    check_profile(profile)
    source = "paper" if profile == "paper" else "cpu"
    checkpoint = str(CHECKPOINT_DIR / checkpoint_name("ant", 64, 0, source))
    if profile == "smoke":
        return PopulationConfig(
            checkpoint,
            n_individuals=8,
            episodes=2,
            episode_length=100,
            sampled_episodes=2,
            mean_network_episodes=16,
        )
    return PopulationConfig(checkpoint, episodes=3)


def evaluate_conditions(config: PopulationConfig, results_dir: Path) -> dict:
    """Returns (N, episodes) of the individuals on every condition, and of the mean network
    (on the same initial states) on ``mean_network_conditions``."""
    return population_on(*load_agent(Path(results_dir) / config.checkpoint), config)


def fig4_config(profile: str) -> PopulationConfig:
    """Figure 4: the individuals on every condition; no mean network."""
    return replace(population_config(profile), mean_network_conditions=())


def fig5_config(profile: str) -> PopulationConfig:
    """Figure 5: the individuals and the mean network on the normal Ant."""
    return replace(population_config(profile), conditions=("normal",))


FIG3_PROFILES = {p: {env: sweep_config(env, p) for env in BACKENDS} for p in PROFILE_NAMES}
FIG4_PROFILES = {p: fig4_config(p) for p in PROFILE_NAMES}
FIG5_PROFILES = {p: fig5_config(p) for p in PROFILE_NAMES}


def _run_population(profile: str, out_dir: Path, env: str, figure: str) -> Path:
    if env != "ant":
        raise ValueError(
            f"env must be 'ant' for {figure} (the variants are Ant bodies), got {env!r}"
        )
    profiles = FIG4_PROFILES if figure == "fig4" else FIG5_PROFILES
    recording = start(profiles, profile, Path(out_dir) / "rl", f"{figure}_{env}")
    config = recording.config
    agent = load_agent(checkpoint_root(out_dir, config.checkpoint) / config.checkpoint)
    returns = population_on(*agent, config)
    results = {"returns": returns}
    if figure == "fig4":
        results["legs"] = compare(returns, "normal", "long_legs")
        results["niches"] = compare(returns, "slippery", "low_gravity")
    else:
        results["mean_network"] = individuals_vs_mean(returns)
        results["authors_protocol"] = authors_protocol(*agent, config)
    return recording.write(results, [config.seed])


def checkpoint_root(out_dir: Path, checkpoint: str) -> Path:
    """Where ``checkpoint`` lies: ``out_dir`` if it has it, else the committed results."""
    return Path(out_dir) if (Path(out_dir) / checkpoint).exists() else committed_results()


def run_fig4(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Figure 4E/F: individuals on normal vs long legs and on two niches."""
    return _run_population(profile, out_dir, env, "fig4")


def run_fig5(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Figure 5: individuals against the mean network."""
    return _run_population(profile, out_dir, env, "fig5")
