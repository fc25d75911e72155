"""Figure 3C at the paper's budget: the Ant under the authors' own training regime,
5 x 10^7 steps, 3 seeds per point.

Every run is ``sgb.rl.regimes.authors_regime`` (their normaliser, entropy draw,
initialisation and evaluation included), the SGB runs with the authors' genome
(``sgb.rl.regimes.with_settings(..., "authors")``: a Gaussian per type pair, as the paper
describes) and, as an ablation, with the type pairs their RL layers alias
(``"authors_aliased"``: ``RL/utils.py`` reads pair (a, b) at entry (a + 1)(b + 1) - 1,
``sgb.genome.aliased_table``). The vanilla network has the SGB's width, 128 (their
``ant_vanilla.yaml`` has 64 and 10^8 steps), so that the comparison isolates the
bottleneck at one budget. Each run is evaluated as the authors evaluate
(``sgb.rl.trainer.Trainer.window_return``, at step 0 and after each tenth): the last
point on the 2048 training environments, the intermediate ones on 256
(``INTERIM_EVAL_ENVS``, the size of the authors' recorded evaluations), which puts the
evaluations near 6 % of a run's CPU time instead of 23 % and leaves what is trained as it
is. Its return is also given on their Figure 3 scale (``sgb.rl.regimes.authors_scale``).

The runs train in the order Figure 3C needs them: vanilla, 128 and 16 types at seeds 0-2
(the fall), then 64 and 32 types at seeds 0-2 (its shape), then the aliased layer at 16
types (does their aliasing move the fall?). Three seeds decide the fall (an SD of 1,500
between seeds gives t near 7.7 for a fall of 6,700); more seeds join only where an
interval cannot yet decide its claim. They are resumable and
shared between processes as Figure 3's are (``sgb.rl.runs.train_runs``,
``sgb.runlock``); after every run the results file is written again from every finished
checkpoint (``"complete": false`` until all are).
"""

import functools
from pathlib import Path

import numpy as np
import pandas as pd

from sgb import claims, resume, stats
from sgb.book import p_text
from sgb.claims import REGIME_SETTINGS, Row, figure3_rows, trained_steps
from sgb.genome import of_params, sigma, softplus
from sgb.profiles import check_profile
from sgb.prose import NOT_RUN, Card, row_texts
from sgb.provenance import results_file
from sgb.queued import Queue, QueuedRun
from sgb.recording import Recording, start
from sgb.results import Records
from sgb.rl import checkpoints
from sgb.rl.regime_runs import RUNS, finished_runs, kept_chunks, run_config, train_regime
from sgb.rl.regimes import arm_name, arm_order, authors_scale, by_arm
from sgb.rl.runs import CHECKPOINT_DIR, finished_run, kept_state, seed_sem
from sgb.schemas import (
    Count,
    Finite,
    List,
    MaybeEmpty,
    NonNegative,
    Positive,
    PpoProvenance,
    Record,
    ResultsFile,
    Return,
    Seconds,
    Seed,
    Training,
)


def run(profile: str, out_dir: Path) -> Path:
    """Train every run not yet trained (each one resumable), writing the results file
    after each."""
    recording = start(PROFILES, profile, Path(out_dir) / "rl", "regime_ant")
    checkpoints = Path(out_dir) / CHECKPOINT_DIR
    write = functools.partial(write_regime, recording, Path(out_dir))
    return train_regime(recording.config, profile, checkpoints, "regime ant", write)


def queued(profile: str, results_dir: Path) -> Queue:
    """The results file and the runs of ``profile`` under ``results_dir``, in the order they
    train, for the background queue (``sgb.grid``)."""
    config = PROFILES[check_profile(profile)]
    runs = []
    for r in config.runs:
        checkpoint = Path(results_dir) / CHECKPOINT_DIR / r.checkpoint(profile)
        state = checkpoint.with_suffix(".state.npz")
        record = finished_run(checkpoint, run_config(config, r))
        progress = resume.peek(state)[1] if record is None and state.exists() else {}
        runs.append(
            QueuedRun(
                label=f"{r.label} seed {r.seed}",
                checkpoint=checkpoint,
                state=state,
                chunks=config.ppo.num_evals,
                finished=record is not None,
                wall_time_s=None if record is None else record["wall_time_s"],
                chunks_done=progress.get("chunks", 0),
                spent_s=progress.get("wall_time_s", 0.0),
                kept=tuple(kept_state(checkpoint, chunk) for chunk in kept_chunks(r)),
                cpu_time_s=None if record is None else record.get("cpu_time_s"),
                spent_cpu_s=progress.get("cpu_time_s"),
            )
        )
    return Queue(results_file(Path(results_dir) / "rl", "regime_ant", profile), tuple(runs))


def write_regime(recording: Recording, out_dir: Path) -> Path:
    """Write every finished run of ``recording.config`` under ``out_dir``: its learning
    curve, its final return on both scales, and per cell-type count the mean over seeds
    with each seed's fraction of the vanilla run of the same seed."""
    config = recording.config
    runs = []
    for r, record in finished_runs(config, recording.profile, out_dir / CHECKPOINT_DIR):
        scaled = authors_scale("ant", record["final_return"])
        run = {"cell_types": r.cell_types, "seed": r.seed, "genome": r.genome}
        if r.cell_types is not None:
            run["layers"] = final_spreads(out_dir / CHECKPOINT_DIR / record["checkpoint"])
        runs.append({**run, "authors_scale": scaled, **record})
    results = {
        "env": "ant",
        "complete": len(runs) == len(config.runs),
        "runs": runs,
        "summary": summarise_regime(runs),
    }
    return recording.write(results, sorted({r["seed"] for r in runs}), parts=runs)


def final_spreads(checkpoint: Path) -> list[dict]:
    """Per SGB layer of the trained actor in ``checkpoint``: its mean sigma and mean |mu|
    over the layer's table entries (a bias layer's too), the spread an individual's
    weights have about their mean against the size of the means."""
    _, params, _, _ = checkpoints.load(checkpoint)
    return [
        {
            "layer": path,
            "mean_sigma": float(np.mean(sigma(g))),
            "mean_abs_mu": float(np.mean(np.abs(g.mu))),
        }
        for path, g in of_params(params.actor).items()
    ]


def spreads(payload: "Regime") -> dict[str, str]:
    """Chapter 5's account of how far the regime's individuals can differ: the spread at
    birth, softplus(rho) at the config's rho start (``regime_birth_sigma``), and over the
    finished SGB runs' layers the trained mean sigma, mean |mu| and their ratio
    (``regime_spreads``)."""
    config = RUNS[payload.provenance.profile]
    first_sgb = next(r for r in config.runs if r.cell_types is not None)
    network = run_config(config, first_sgb).network
    at_birth = float(softplus(network.rho_init))
    birth = f"{at_birth:.2g} (rho {network.rho_init:g} ± {network.rho_init_std:g})"
    layers = [layer for r in payload.results.runs for layer in (r.layers or [])]
    if not layers:
        return {"regime_birth_sigma": birth, "regime_spreads": NOT_RUN}
    spread = [x.mean_sigma for x in layers]
    mu = [x.mean_abs_mu for x in layers]
    ratio = [100 * x.mean_sigma / x.mean_abs_mu for x in layers]
    runs = sum(1 for r in payload.results.runs if r.layers)
    return {
        "regime_birth_sigma": birth,
        "regime_spreads": f"mean sigma {min(spread):.2g} to {max(spread):.2g} per layer against "
        f"a mean |mu| of {min(mu):.2g} to {max(mu):.2g}, so an individual's weights lie "
        f"{min(ratio):.1f} to {max(ratio):.1f} % of their size from the means ({runs} runs, "
        f"{len(layers)} layers)",
    }


def sigma_course(run: "RegimeRun") -> tuple[np.ndarray, np.ndarray, list[str]] | None:
    """The recorded course of ``run``'s spreads: (env steps (n,), the mean sigma of each SGB
    kernel (n, layers), the layers' names), over the n >= 2 evaluations that recorded
    them, the biases left out; None for a run with fewer."""
    kept = [(s, d) for s, d in zip(run.eval_steps, run.eval_sigmas or [], strict=False) if d]
    if len(kept) < 2:
        return None
    names = [name for name in kept[0][1] if not name.endswith("/bias")]
    steps = np.array([s for s, _ in kept], dtype=float)
    return steps, np.array([[d[name] for name in names] for _, d in kept]), names


def sigma_courses_by_run(payload: "Regime") -> dict[str, tuple]:
    """Each SGB run's recorded course of its spreads (``sigma_course``), by the run's name
    (``16 types, pairs aliased seed 2``), in the file's order; runs that recorded fewer
    than two evaluations are left out."""
    return {
        f"{arm_name(run.cell_types, run.genome)} seed {run.seed}": course
        for run in payload.results.runs
        if run.cell_types is not None and (course := sigma_course(run)) is not None
    }


def sigma_courses(payload: "Regime") -> dict[str, str]:
    """How the spreads moved over training (``regime_sigma_course``), per SGB run that
    recorded them (``sigma_courses_by_run``): its kernels' mean sigma at its first
    recorded evaluation and at its last, and the change; ``NOT_RUN`` where no run
    recorded two."""
    found = []
    for name, (steps, sigmas, _) in sigma_courses_by_run(payload).items():
        first, last = sigmas[0].mean(), sigmas[-1].mean()
        found.append(
            f"{name}, {first:.2g} at {_millions(steps[0])} to "
            f"{last:.2g} at {_millions(steps[-1])} ({last / first - 1:+.0%})"
        )
    return {"regime_sigma_course": "; ".join(found) or NOT_RUN}


def _millions(steps: float) -> str:
    return "step 0" if steps == 0 else f"{steps / 1e6:.3g}M steps"


def summarise_regime(runs: list[dict]) -> list[dict]:
    """Per genome and cell-type count (vanilla first): seeds, mean final return and SEM,
    mean on the authors' scale, and the fraction of vanilla over the seeds that have a
    vanilla run."""
    vanilla = {r["seed"]: r["final_return"] for r in runs if r["cell_types"] is None}
    out = []
    for genome, k in dict.fromkeys((r.get("genome", "authors"), r["cell_types"]) for r in runs):
        mine = [r for r in runs if (r.get("genome", "authors"), r["cell_types"]) == (genome, k)]
        returns = np.array([r["final_return"] for r in mine])
        paired = [r["final_return"] / vanilla[r["seed"]] for r in mine if r["seed"] in vanilla]
        out.append(
            {
                "cell_types": k,
                "genome": genome,
                "seeds": [r["seed"] for r in mine],
                "mean_return": float(returns.mean()),
                "sem_return": seed_sem(returns),
                "mean_authors_scale": float(np.mean([r["authors_scale"] for r in mine])),
                "fraction_of_vanilla": float(np.mean(paired)) if paired else None,
            }
        )
    return out


# the registry reads an experiment's profiles here
PROFILES = RUNS


# The ablation trained at 16 types alone -> the genome whose 128-type runs its fall leaves.
ABLATIONS = {"authors_aliased": "authors"}


def regime_rows(runs: list["RegimeRun"], steps: int) -> list[Row]:
    """Figure 3C at the paper's budget (``sgb.experiments.regime``): the level at 128 types,
    the fall to 16 and its shape under the authors' regime, each run scored by its last
    evaluation (the authors' window on all 2,048 training environments); with their
    Gaussian per pair, and the fall from its 128 types to their aliased pairs at 16
    (``ABLATIONS``). A row appears once the arms it compares have two seeds each."""
    return figure3_rows(
        runs,
        "ant",
        steps,
        "final_return",
        REGIME_SETTINGS,
        key_infix="regime.",
        settings_of=lambda r: r.genome,
        on_authors_scale=functools.partial(authors_scale, "ant"),
        ablations=ABLATIONS,
    )


def aliasing(runs: list["RegimeRun"]) -> str:
    """What their aliased pairs do at 16 types: the aliased arm's mean final return less
    the per-pair Gaussian's, in fractions of vanilla's mean, with Welch's 95 % interval
    and p; "not yet" while either arm has fewer than two seeds."""

    def returns(genome: str, k: int | None) -> np.ndarray:
        return claims.run_returns(runs, genome, k, "final_return", lambda r: r.genome)

    aliased, per_pair = returns("authors_aliased", 16), returns("authors", 16)
    if min(aliased.size, per_pair.size) < 2:
        return f"not yet (seeds: aliased {aliased.size}, per pair {per_pair.size}; two each needed)"
    scale = returns("ours", None).mean()  # vanilla's
    t = stats.welch(aliased / scale, per_pair / scale)
    return (
        f"{t.estimate:+.2f} [{t.low:+.2f}, {t.high:+.2f}] of vanilla (Welch, p = {p_text(t.p)}; "
        f"seeds: aliased {aliased.size}, per pair {per_pair.size})"
    )


def _seeds(n: int) -> str:
    return f"{n} seed" + ("" if n == 1 else "s")


def _cpu_per_run(runs: list["RegimeRun"]) -> str:
    """The mean CPU time of the runs, of every arm, that recorded it (a pause and the
    time their core gave to other work not counted)."""
    recorded = [r.cpu_time_s for r in runs if r.cpu_time_s is not None]
    if not recorded:
        return "not recorded by the runs finished so far"
    return f"{np.mean(recorded) / 3600:.1f} h ({len(recorded)} of {len(runs)} runs recorded it)"


def regime(payload: "Regime") -> dict[str, str]:
    """The authors' regime (``rl/regime_ant_cpu.json``), from its summary per arm (mean
    final return over seeds): vanilla's mean with its SEM and seeds, its env steps, its mean
    on the authors' scale, its mean env-steps/s and wall time per run, the mean CPU time
    per run of any arm where recorded (``regime_*``),
    ``regime_sgb``: each SGB arm's mean as a fraction of vanilla's, with its seeds (in
    ``arm_order``), and the
    scorecard's rows of the level at 128 types, the fall to 16 and the fall's shape with
    the authors' genome, and the fall to their aliased pairs (``regime_level``,
    ``regime_fall``, ``regime_shape``, ``regime_fall_aliased``: estimate, interval and
    verdict; "no row yet" while an arm they compare has fewer than two seeds), and what
    the aliasing does at 16 types (``regime_aliasing``, ``aliasing``)."""
    runs, summary = payload.results.runs, payload.results.summary
    card = claims.by_key(regime_rows(runs, trained_steps(payload)))
    texts = {}
    fig3 = [(name, stem, "authors") for name, stem in claims.FIG3_KEYS.items()]
    aliased = ("fall_aliased", claims.FIG3_KEYS["fall"], "authors_aliased")
    for name, stem, genome in [*fig3, aliased]:
        setting = claims.figure3_setting("ant", genome, REGIME_SETTINGS, ABLATIONS)
        row = next((r for r in card.get(f"{stem}.regime.ant", []) if r.setting == setting), None)
        found = row_texts("row", row)
        texts[f"regime_{name}"] = (
            "no row yet (an arm it compares has fewer than two seeds)"
            if row is None
            else f"{found['row_ours']}, {found['row_verdict']}"
        )
    vanilla = next(s for s in summary if s.cell_types is None)
    mine = [r for r in runs if r.cell_types is None]
    n = len(vanilla.seeds)
    spread = "" if vanilla.sem_return is None else f" ± {vanilla.sem_return:.0f} (SEM)"
    arms = sorted(
        (s for s in summary if s.cell_types is not None),
        key=lambda s: arm_order(s.cell_types, s.genome),
    )
    return {
        "regime_vanilla": f"{vanilla.mean_return:.0f}{spread} over {_seeds(n)}",
        "regime_steps": f"{mine[0].eval_steps[-1]:,}",
        "regime_vanilla_scale": f"{vanilla.mean_authors_scale:.2f}",
        "regime_speed": f"{np.mean([r.train_steps_per_s for r in mine]):,.0f}",
        "regime_wall": f"{np.mean([r.wall_time_s for r in mine]) / 3600:.1f} h",
        "regime_cpu": _cpu_per_run(runs),
        "regime_aliasing": aliasing(runs),
        "regime_sgb": "; ".join(
            f"{arm_name(s.cell_types, s.genome)}: {s.fraction_of_vanilla:.2f} of vanilla "
            f"({_seeds(len(s.seeds))})"
            for s in arms
        )
        or "none",
    } | texts


def evidence(records: Records) -> list[Row]:
    """Figure 3C under the authors' regime (``regime_rows``)."""
    payload = records.get("regime")
    return [] if payload is None else regime_rows(payload.results.runs, trained_steps(payload))


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 5 glues of the regime's runs (``regime``, ``spreads``,
    ``sigma_courses``)."""
    payload = records("regime")
    return regime(payload) | spreads(payload) | sigma_courses(payload)


REGIME_COLUMNS = {
    "cell_types": "cell types",
    "seed": "seed",
    "final_return": "final return",
    "last_two_return": "mean of last two returns",
    "authors_scale": "final, authors' scale",
    "train_steps_per_s": "env steps/s",
    "wall_time_s": "wall time (s)",
    "cpu_time_s": "CPU time (s)",
}


def regime_table(payload: "Regime") -> pd.DataFrame:
    """The authors' regime (``sgb.experiments.regime``), one row per run: final and
    last-two evaluation returns, the final one on the authors' Figure 3 scale, training
    env-steps/s, wall time and CPU time ("-" where not recorded); columns named as
    ``REGIME_COLUMNS`` maps the files' keys."""
    runs = pd.DataFrame([r.model_dump() for r in payload.results.runs])[list(REGIME_COLUMNS)]
    return runs.rename(columns=REGIME_COLUMNS)


def _mean_sem(values: list[float], digits: int) -> str:
    """``mean ± SEM`` over seeds, the mean alone for one seed."""
    values = np.asarray(values)
    sem = seed_sem(values)
    return f"{values.mean():.{digits}f}" + ("" if np.isnan(sem) else f" ± {sem:.{digits}f}")


def sweep_table(payload: "Regime") -> pd.DataFrame:
    """Figure 3C at the paper's budget on both scales, one row per arm (in ``arm_order``):
    its seeds, the mean final return, the mean fraction of the same seed's vanilla return
    (the paper's text), and the mean on the authors' scale, (R + 724) / (8706 + 724) (their
    code's plot), each ``mean ± SEM`` over seeds."""
    runs = payload.results.runs
    vanilla = {r.seed: r.final_return for r in runs if r.cell_types is None}
    rows = []
    for (cell_types, genome), mine in by_arm(runs).items():
        paired = [r.final_return / vanilla[r.seed] for r in mine if r.seed in vanilla]
        rows.append(
            {
                "arm": arm_name(cell_types, genome),
                "seeds": ", ".join(str(r.seed) for r in mine),
                "final return": _mean_sem([r.final_return for r in mine], 0),
                "fraction of vanilla": _mean_sem(paired, 2) if paired else "-",
                "authors' scale": _mean_sem([r.authors_scale for r in mine], 2),
            }
        )
    return pd.DataFrame(rows)


class LayerSpread(Record):
    layer: str
    mean_sigma: NonNegative
    mean_abs_mu: NonNegative


class RegimeRun(Training):
    genome: str
    layers: MaybeEmpty[LayerSpread] | None = None  # an SGB run's, once written with them
    # per evaluation, the actor's mean sigma per SGB layer (``sgb.genome.layer_sigmas``),
    # None for an evaluation made before runs recorded it; absent from older runs
    eval_sigmas: List[dict[str, Positive] | None] | None = None
    authors_scale: Finite
    train_steps_per_s: Positive
    wall_time_s: Seconds
    cpu_time_s: Seconds | None = None  # absent from runs trained before runs recorded it


class RegimeSummary(Record):
    """One arm: its seeds' mean final return, on the authors' scale too, and its mean
    fraction of the vanilla run of the same seed (null without one)."""

    cell_types: Count | None
    genome: str
    seeds: List[Seed]
    mean_return: Return
    sem_return: NonNegative | None
    mean_authors_scale: Finite
    fraction_of_vanilla: Finite | None


class RegimeResults(Record):
    env: str
    runs: List[RegimeRun]
    summary: List[RegimeSummary]


class Regime(ResultsFile):
    provenance: PpoProvenance
    results: RegimeResults
