"""Whether the agents of the regime grid walk: each finished run of ``sgb.experiments.regime``
played on the authors' evaluation window (``sgb.rl.trainer.Trainer.window_gait``), its
return and each environment's mean forward velocity over the window.

A return says how well an agent does, not what it does: the Ant earns 1 per step for staying
upright (Brax's ``healthy_reward``) and its forward velocity in m/s for moving (its
``forward_reward``), so an agent that stands still for the 1000 steps of an episode earns
about 1000, while a walking one earns several thousand. A run walks if its forward velocity,
averaged over the window's environments, is at least ``WALKING_SPEED``, 1 m/s: the speed at
which moving forward earns as much per step as staying upright. So a fall of the return
at few cell types can be told apart as agents that walk less well (the paper's capacity) or
agents that have not learned to walk at all.

The runs are those of the regime's profile; a run not yet trained is left out (and evaluated
by a later run of this experiment), one already in the results file is not evaluated again.
"""

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import jax
import numpy as np
import pandas as pd
from pydantic import Field

from sgb import runlock, validation
from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.prose import NOT_RUN, Card
from sgb.provenance import git_commit, results_file
from sgb.queued import Queue, file_run
from sgb.recording import Recording, held_results, start
from sgb.results import Records
from sgb.rl import checkpoints
from sgb.rl.ppo import PPOConfig
from sgb.rl.regime_runs import RUNS, RegimeRun, run_config
from sgb.rl.regimes import arm_name, by_arm
from sgb.rl.runs import CHECKPOINT_DIR, checkpoint_root, finished_run
from sgb.rl.trainer import make_trainer
from sgb.schemas import (
    MAX_SPEED,
    Count,
    Finite,
    MaybeEmpty,
    NonNegative,
    Positive,
    Record,
    ResultsFile,
    Return,
    Seed,
    Speed,
)
from sgb.timing import timed

WALKING_SPEED = 1.0  # m/s: the forward reward per step equals the healthy reward (1)


@dataclass(frozen=True)
class GaitConfig:
    """Which profile's regime runs to play, on how many environments, from which seed."""

    regime_profile: str
    n_envs: int = 256
    seed: int = 0

    def __post_init__(self) -> None:
        check_profile(self.regime_profile)
        validation.integer("n_envs", self.n_envs, minimum=2)
        validation.seed("seed", self.seed)


def gait_config(profile: str) -> GaitConfig:
    """The regime runs of ``profile`` on 256 environments (4 at smoke)."""
    check_profile(profile)
    return GaitConfig(profile, n_envs=4 if profile == "smoke" else 256)


def gait(ppo: PPOConfig, params, normalizer, n_envs: int, seed: int) -> dict:
    """The window return and the forward velocity (m/s) of an agent: its mean over the
    ``n_envs`` environments, their SEM, and whether it walks (``WALKING_SPEED``); and
    what the return is made of (``Trainer.window_gait``): the episodes ended per
    environment, the reward and the control cost per step, each a mean over the
    environments."""
    trainer = make_trainer(ppo.step_settings())
    key = jax.random.PRNGKey(validation.seed("seed", seed))
    ret, per_env = trainer.window_gait(params, normalizer, key, n_envs)
    per_env = {k: np.asarray(v, dtype=np.float64) for k, v in per_env.items()}
    velocity = per_env["velocity"]
    mean = float(velocity.mean())
    return {
        "window_return": float(ret),
        "forward_velocity": mean,
        "forward_velocity_sem": float(velocity.std(ddof=1) / np.sqrt(velocity.size)),
        "walks": mean >= WALKING_SPEED,
        "episodes_per_env": float(per_env["episodes"].mean()),
        "reward_per_step": float(per_env["reward"].mean()),
        "control_cost": float(per_env["control_cost"].mean()),
    }


def run(profile: str, out_dir: Path) -> Path:
    """Play every finished regime run of the profile not yet in the results file, writing
    the file after each; returns its path. One process at a time plays into the file
    (another returns at once): the background queue's workers may both reach it."""
    recording = start(PROFILES, profile, Path(out_dir) / "rl", "regime_gait_ant")
    with runlock.claim(recording.path.with_suffix("")) as mine:
        if not mine:
            print(f"another process is playing into {recording.path}; it is left to it")
            return recording.path
        return _play(recording, Path(out_dir))


def _play(recording: Recording, out_dir: Path) -> Path:
    config, regime = recording.config, RUNS[recording.config.regime_profile]
    runs = list(recording.earlier().get("runs", []))
    done = {(r["cell_types"], r["seed"], r["genome"]) for r in runs}
    for i, r in enumerate(regime.runs):
        if (r.cell_types, r.seed, r.genome) in done:
            continue
        if (checkpoint := _landed(r, config.regime_profile, out_dir)) is None:
            continue
        print(f"regime gait {r.label} seed {r.seed} ({i + 1}/{len(regime.runs)})", flush=True)
        runs.append(_played(r, checkpoint, config))
        _write(recording, runs)
    return _write(recording, runs)


def _landed(r: RegimeRun, regime_profile: str, out_dir: Path) -> Path | None:
    """The checkpoint of regime run ``r`` under ``out_dir`` (else the committed one), or
    None while its training has not finished."""
    name = str(Path(CHECKPOINT_DIR) / r.checkpoint(regime_profile))
    checkpoint = checkpoint_root(out_dir, name) / name
    finished = finished_run(checkpoint, run_config(RUNS[regime_profile], r))
    return None if finished is None else checkpoint


def queued(profile: str, results_dir: Path) -> Queue:
    """The gait of every run of the regime at ``profile`` under ``results_dir``, in the
    order they train, one chunk each, for the background queue (``sgb.grid``), which
    plays the landed ones each time it starts; a run whose training has not landed is
    labelled so."""
    config = PROFILES[check_profile(profile)]
    path = results_file(Path(results_dir) / "rl", "regime_gait_ant", profile)
    runs = held_results(path, config).get("runs", [])
    played = {(r["cell_types"], r["seed"], r["genome"]): r for r in runs}
    listed = []
    for r in RUNS[config.regime_profile].runs:
        landed = _landed(r, config.regime_profile, Path(results_dir)) is not None
        label = f"{r.label} seed {r.seed}{'' if landed else ' (its training has not landed)'}"
        record = played.get((r.cell_types, r.seed, r.genome))
        listed.append(file_run(label, path, f"{r.label}_s{r.seed}", record))
    return Queue(path, tuple(listed))


def _played(r: RegimeRun, checkpoint: Path, config: GaitConfig) -> dict:
    with timed() as spent:
        ppo, params, normalizer, _ = checkpoints.load(checkpoint)
        record = gait(ppo, params, normalizer, config.n_envs, config.seed)
    run = {"cell_types": r.cell_types, "seed": r.seed, "genome": r.genome}
    return {**run, **record, **spent, "git_commit": git_commit()}


def _write(recording: Recording, runs: list[dict]) -> Path:
    runs = sorted(runs, key=lambda r: (r["genome"], r["cell_types"] or 0, r["seed"]))
    results = {"env": "ant", "walking_speed": WALKING_SPEED, "runs": runs}
    return recording.write(results, sorted({r["seed"] for r in runs}), parts=runs)


PROFILES = {p: gait_config(p) for p in PROFILE_NAMES}


def regime_gait(results: "RegimeGaitResults | None") -> dict[str, str]:
    """Whether the regime's agents walk (the results of ``sgb.experiments.regime_gait``):
    each arm's runs' forward speeds by seed (``gait_runs``), how many walk, at least the
    file's walking speed (``gait_walks``), and each arm's episodes ended per environment
    in the window (``gait_episodes``: 1 where no agent falls more than once in an
    environment, ``Trainer.window_gait``)."""
    runs = [] if results is None else results.runs
    if not runs:
        return dict.fromkeys(("gait_runs", "gait_walks", "gait_episodes"), NOT_RUN)
    walking = sum(r.walks for r in runs)
    speed = results.walking_speed
    return {
        "gait_runs": _by_arm(runs, lambda r: r.forward_velocity, " m/s"),
        "gait_walks": f"{walking} of the {len(runs)} runs walk (at least {speed:g} m/s)",
        "gait_episodes": _by_arm(runs, lambda r: r.episodes_per_env, ""),
    }


def _by_arm(runs: list["GaitRun"], value: Callable[["GaitRun"], float], unit: str) -> str:
    """Each arm's runs' ``value`` by seed, in ``sgb.rl.regimes.arm_order``: e.g.
    ``vanilla PPO 7.39, 7.32 m/s (seeds 0, 1); 16 types 1.23 m/s (seed 0)``."""
    arms = []
    for (cell_types, genome), mine in by_arm(runs).items():
        values = ", ".join(f"{value(r):.2f}" for r in mine)
        seeds = ", ".join(str(r.seed) for r in mine)
        which = f"seed{'s' * (len(mine) > 1)} {seeds}"
        arms.append(f"{arm_name(cell_types, genome)} {values}{unit} ({which})")
    return "; ".join(arms)


GAIT_COLUMNS = {
    "seed": "seed",
    "window_return": "window return",
    "forward_velocity": "forward speed (m/s)",
    "episodes_per_env": "episodes per environment",
    "reward_per_step": "reward per step",
    "control_cost": "control cost per step",
}


def gait_table(payload: "RegimeGait") -> pd.DataFrame:
    """The regime's gaits, one row per run, arm by arm (``sgb.rl.regimes.by_arm``): what
    its window return is made of (the return is 1000 x the reward per step / the episodes
    per environment); its arm, then columns named as ``GAIT_COLUMNS`` maps the file's
    keys."""
    arms = by_arm(payload.results.runs).items()
    rows = [{"arm": arm_name(*arm)} | r.model_dump() for arm, mine in arms for r in mine]
    table = pd.DataFrame(rows)[["arm", *GAIT_COLUMNS]]
    return table.rename(columns=GAIT_COLUMNS)


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 5 glues of the regime's gaits (``regime_gait``)."""
    payload = records.get("regime_gait")
    return regime_gait(None if payload is None else payload.results)


class GaitRun(Record):
    cell_types: Count | None
    seed: Seed
    genome: str
    window_return: Return
    forward_velocity: Speed
    forward_velocity_sem: Annotated[float, Field(ge=0, le=MAX_SPEED)]
    walks: bool
    episodes_per_env: NonNegative
    reward_per_step: Finite
    control_cost: NonNegative


class RegimeGaitResults(Record):
    walking_speed: Positive
    runs: MaybeEmpty[GaitRun]


class RegimeGait(ResultsFile):
    results: RegimeGaitResults
