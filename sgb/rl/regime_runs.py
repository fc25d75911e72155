"""The runs of Figure 3C at the paper's budget under the authors' own training regime
(``sgb.experiments.regime`` trains them): each run's cell types, seed and genome settings,
their order, their PPO settings and checkpoint names, at each profile (``RUNS``)."""

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from sgb import validation
from sgb.profiles import PROFILE_NAMES, check_profile
from sgb.rl.ppo import PPOConfig
from sgb.rl.regimes import authors_regime, with_settings
from sgb.rl.runs import checkpoint_name, finished_run, train_runs
from sgb.rl.sweep import ppo_settings

GENOMES = ("authors", "authors_aliased")  # a Gaussian per type pair; their aliased layers
SEEDS = tuple(range(3))
INTERIM_EVAL_ENVS = 256  # environments of every evaluation but the last
# The 64-type runs keep their state after chunk 2 of 10 (10^7 of the 5 x 10^7 steps): their
# genome part-way through training, for the populations (does variability fall with it?).
KEPT_CHUNKS = {64: (2,)}  # cell types -> chunks


@dataclass(frozen=True)
class RegimeRun:
    """One run: its cell types (``None``: vanilla), seed and genome settings (``GENOMES``;
    a vanilla run's is ``"authors"``, which it does not read)."""

    cell_types: int | None
    seed: int
    genome: str = "authors"

    def __post_init__(self) -> None:
        validation.seed("seed", self.seed)
        validation.choice("genome", self.genome, GENOMES)
        if self.cell_types is not None:
            validation.integer("cell types", self.cell_types)
        elif self.genome != "authors":
            raise ValueError("a vanilla run has no genome to alias")

    @property
    def label(self) -> str:
        """``vanilla``, ``k64`` or ``k64_aliased``."""
        if self.cell_types is None:
            return "vanilla"
        return f"k{self.cell_types}" + ("_aliased" if self.genome == "authors_aliased" else "")

    def checkpoint(self, profile: str) -> str:
        """File name of its checkpoint at ``profile`` (``sgb.rl.runs.checkpoint_name``)."""
        aliased = self.genome == "authors_aliased"
        return checkpoint_name(
            "ant", self.cell_types, self.seed, profile, "authors", regime=True, aliased=aliased
        )


@dataclass(frozen=True)
class RegimeRuns:
    """The runs in the order they train, and the PPO settings they share before
    ``run_config`` makes each one."""

    runs: tuple[RegimeRun, ...]
    ppo: PPOConfig

    def __post_init__(self) -> None:
        for r in self.runs:
            validation.instance("run", r, RegimeRun)


def grid(seeds: tuple[int, ...] = SEEDS) -> tuple[RegimeRun, ...]:
    """Figure 3C's runs in the order they train (the docstring of ``sgb.experiments.regime``)."""
    fall = [RegimeRun(k, s) for s in seeds for k in (None, 128, 16)]
    shape = [RegimeRun(k, s) for k in (64, 32) for s in seeds]
    aliased = [RegimeRun(16, s, "authors_aliased") for s in seeds]
    return (*fall, *shape, *aliased)


def regime_config(profile: str) -> RegimeRuns:
    """The runs at ``profile``: at ``cpu`` and ``paper`` the whole grid (18 runs of
    5 x 10^7 steps); smoke is a vanilla and a 16-type run of a few hundred steps."""
    check_profile(profile)
    regime = authors_regime(ppo_settings("ant", "cpu"))
    base = replace(regime, interim_eval_individuals=INTERIM_EVAL_ENVS)
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
            interim_eval_individuals=2,
            episode_length=64,
        )
        return RegimeRuns((RegimeRun(None, 0), RegimeRun(16, 0)), ppo)
    return RegimeRuns(grid(), base)


def run_config(config: RegimeRuns, run: RegimeRun) -> PPOConfig:
    """The settings of ``run``: the regime's network at its cell types, under the authors'
    genome settings for an SGB, its type pairs aliased for an ``"authors_aliased"`` run."""
    sgb = run.cell_types is not None
    network = replace(config.ppo.network, cell_types=run.cell_types, bayesian_biases=sgb)
    ppo = replace(config.ppo, network=network)
    if not sgb:
        return ppo
    ppo = with_settings(ppo, "authors")
    aliased = run.genome == "authors_aliased"
    return replace(ppo, network=replace(ppo.network, aliased_pairs=aliased))


def train_regime(
    config: RegimeRuns, profile: str, checkpoints: Path, name: str, write: Callable[[], Path]
) -> Path:
    """Train each run of ``config`` not yet trained into ``checkpoints``, keeping the states
    of ``kept_chunks`` (``sgb.rl.runs.
    train_runs``, labelled ``name``), calling ``write`` after each; the results file."""
    runs = [
        (
            f"{name} {r.label} seed {r.seed}",
            run_config(config, r),
            r.seed,
            checkpoints / r.checkpoint(profile),
        )
        for r in config.runs
    ]
    kept = {checkpoints / r.checkpoint(profile): kept_chunks(r) for r in config.runs}
    return train_runs(runs, profile, write, kept.__getitem__)


def kept_chunks(run: RegimeRun) -> tuple[int, ...]:
    """The chunks after which ``run`` keeps its training state (``KEPT_CHUNKS``; not for
    an aliased run)."""
    return KEPT_CHUNKS.get(run.cell_types, ()) if run.genome == "authors" else ()


def steps_at(config: RegimeRuns, chunk: int) -> int:
    """The environment steps a run of ``config`` has trained after ``chunk``."""
    ppo = config.ppo
    return chunk * max(1, ppo.iterations // ppo.num_evals) * ppo.steps_per_iteration


def finished_runs(
    config: RegimeRuns, profile: str, checkpoints: Path
) -> list[tuple[RegimeRun, dict]]:
    """Each run of ``config`` whose checkpoint under ``checkpoints`` is finished, with its
    record (``sgb.rl.runs.finished_run``: learning curve, final return, speed, wall time),
    in the order of ``config.runs``."""
    found = []
    for r in config.runs:
        record = finished_run(checkpoints / r.checkpoint(profile), run_config(config, r))
        if record is not None:
            found.append((r, record))
    return found


RUNS = {p: regime_config(p) for p in PROFILE_NAMES}
