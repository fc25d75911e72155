"""An RL run's checkpoint: its name (``checkpoint_name``, the one name of every run's
checkpoint: Figure 3, the spread sweep, the regime), where it lies (a results
directory or the committed results, ``checkpoint_root``), training the run once
(``trained_run``: resumable, and reused where the checkpoint holds its settings), the
one loop over a sweep's runs (``train_runs``: each process the runs no other holds) and
reading its record back (``finished_run``); the SEM over a summary's seeds."""

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from sgb import runlock, stats, validation
from sgb.paths import committed_results
from sgb.provenance import provenance
from sgb.rl import checkpoints
from sgb.rl.agent import NetworkConfig
from sgb.rl.ppo import PPOConfig, train

CHECKPOINT_DIR = Path("rl") / "checkpoints"


def checkpoint_name(
    env: str,
    cell_types: int | None,
    seed: int,
    profile: str,
    settings: str = "ours",
    rho_init: float = NetworkConfig.rho_init,
    regime: bool = False,
    aliased: bool = False,
) -> str:
    """File name of one run's checkpoint, the one name of every RL run:
    ``<env>[_regime]_<vanilla|k<cell_types>>[_<settings>][_aliased][_rho<rho_init>]_s<seed>_<profile>.msgpack``.

    ``regime``: trained under the authors' regime at the paper's budget
    (``sgb.rl.regime_runs``), whose own genome settings are the authors'; under ours
    (Figure 3, the spread sweep) they are ours. ``settings`` is named where it is not the
    regime's own, ``aliased`` (the authors' aliased type pairs) where set and ``rho_init``
    where it is not ``NetworkConfig``'s (the spread sweep)."""
    label = "vanilla" if cell_types is None else f"k{cell_types}"
    if settings != ("authors" if regime else "ours"):
        label += f"_{settings}"
    if aliased:
        label += "_aliased"
    if rho_init != NetworkConfig.rho_init:
        label += f"_rho{rho_init:g}"
    prefix = f"{env}_regime" if regime else env
    return f"{prefix}_{label}_s{seed}_{profile}.msgpack"


def checkpoint_root(out_dir: Path, checkpoint: str) -> Path:
    """Where ``checkpoint`` lies: ``out_dir`` if it has it, else the committed results."""
    return Path(out_dir) if (Path(out_dir) / checkpoint).exists() else committed_results()


def kept_state(checkpoint: Path, chunk: int) -> Path:
    """Where the run of ``checkpoint`` keeps its training state after ``chunk``
    (``sgb.rl.ppo.train``'s ``keep``): ``<checkpoint stem>.chunk<chunk>.npz`` beside it."""
    return checkpoint.with_name(f"{checkpoint.stem}.chunk{chunk}.npz")


def trained_run(
    ppo: PPOConfig,
    seed: int,
    checkpoint: Path,
    profile: str,
    label: str,
    keep: tuple[int, ...] = (),
) -> bool:
    """Make sure ``checkpoint`` holds ``ppo`` trained with ``seed``: train it unless it
    does (a killed run continues from its training state, ``*.state.npz``, kept beside
    it), keeping its state after each chunk of ``keep`` (``kept_state``); returns whether
    it trained now. ``label`` names the run in what it prints."""
    if finished_run(checkpoint, ppo) is not None:
        print(f"{label}: reused {checkpoint}", flush=True)
        return False
    state_file = checkpoint.with_suffix(".state.npz")
    print(f"{label}: {'resumed' if state_file.exists() else 'training'}", flush=True)
    kept = {chunk: kept_state(checkpoint, chunk) for chunk in keep}
    result = train(ppo, seed=seed, state_file=state_file, label=label, keep=kept)
    checkpoints.save(checkpoint, result, provenance(ppo, profile, [seed], result.wall_time_s))
    state_file.unlink()
    return True


def train_runs(
    runs: Sequence[tuple[str, PPOConfig, int, Path]],
    profile: str,
    write: Callable[[], Path],
    keep: Callable[[Path], tuple[int, ...]] = lambda checkpoint: (),
) -> Path:
    """Train each of ``runs`` (a label, its settings, seed and checkpoint), in order, that
    no other process holds (``sgb.runlock``), each once (``trained_run``, keeping the
    states after the chunks ``keep`` names for its checkpoint), calling ``write`` (the
    results file from every finished checkpoint) after each run trained and once at the
    end; returns what that last ``write`` returns."""
    for i, (label, ppo, seed, checkpoint) in enumerate(runs):
        label = f"{label} ({i + 1}/{len(runs)})"
        with runlock.claim(checkpoint) as mine:
            if not mine:
                print(f"{label}: another process is training it", flush=True)
                continue
            if trained_run(ppo, seed, checkpoint, profile, label, keep(checkpoint)):
                write()
    return write()


def finished_run(checkpoint: Path, ppo: PPOConfig) -> dict | None:
    """The record kept in ``checkpoint`` if it holds a run trained with ``ppo`` (``None``
    if there is none, or it was trained with other settings; its intermediate evaluations
    may have had another size, ``PPOConfig.trains_as``): its learning curve, its
    scores (the last evaluation; the mean of the last two), its speed, wall time, CPU time
    (where recorded) and the commit and date it was trained at. A damaged
    checkpoint counts as none (it is said so), so that the sweep trains the run again."""
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
        **({"cpu_time_s": meta["cpu_time_s"]} if meta.get("cpu_time_s") is not None else {}),
        **({"eval_sigmas": meta["eval_sigmas"]} if meta.get("eval_sigmas") else {}),
        "git_commit": trained.get("git_commit", "not recorded"),
        "date": trained.get("date", "not recorded"),
        "checkpoint": checkpoint.name,
    }


def seed_sem(values: np.ndarray) -> float:
    """SEM over seeds of a 1-D array; NaN for a single seed."""
    return float(stats.sem(values)) if values.size > 1 else float("nan")
