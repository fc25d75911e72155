"""Figure 3: return against the number of cell types (SGB-PPO on Brax).

Trains vanilla PPO and SGB-PPO at several cell-type counts (hidden width 128) for several
seeds on one environment (the sweep: ``sgb.rl.sweep``); the innate return of the SGB
agents as a fraction of the vanilla agent's. Writes the checkpoint of every run
(``sgb.rl.runs``).
"""

import functools
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from sgb import stats, verdicts
from sgb.claims import (
    CLAIMS,
    FIG3_KEYS,
    Row,
    figure3_rows,
    judge,
    room_above_floor,
    run_returns,
    trained_steps,
)
from sgb.profiles import PROFILE_NAMES
from sgb.prose import GENOMES, NOT_RUN, Card, row_of, row_texts
from sgb.provenance import read_results
from sgb.recording import Recording, start
from sgb.results import Records
from sgb.rl.agent import NetworkConfig
from sgb.rl.ppo import PPOConfig
from sgb.rl.regimes import authors_scale, with_settings
from sgb.rl.runs import CHECKPOINT_DIR, checkpoint_name, finished_run, seed_sem, train_runs
from sgb.rl.sweep import BACKENDS, CellTypeSweep, sweep_config
from sgb.schemas import (
    Count,
    Finite,
    List,
    NonNegative,
    PpoProvenance,
    Record,
    ResultsFile,
    Return,
    Training,
)


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


def typing_rows(runs: list["Fig3Run"], steps: int, score: str = "last_two_return") -> list[Row]:
    """Chapter 5's explanation of the fall at 16 types under the authors' genome: typing
    the observation entries. Each ablation swaps the input typing alone."""
    vanilla = run_returns(runs, "ours", None, score).mean()
    pairs = [
        ("authors_untyped_inputs", "authors", "the authors' genome, inputs untyped vs typed"),
        ("ours", "ours_typed_inputs", "our genome, inputs untyped vs typed"),
    ]
    rows = []
    for untyped, typed, label in pairs:
        a, b = run_returns(runs, untyped, 16, score), run_returns(runs, typed, 16, score)
        if min(a.size, b.size) < 2:
            continue
        rows.append(
            judge(
                "ch5.typing_explains_fall",
                label,
                stats.welch(a / vanilla, b / vanilla),
                f"{steps / 1e6:g}M steps, seeds {a.size} and {b.size}",
                room=room_above_floor(a, vanilla, "the untyped agents"),
            )
        )
    return rows


def untrained_row(env: str, steps: int) -> Row:
    """Figure 3 on a body whose vanilla agent learned nothing in ``steps``: no fraction of
    vanilla means anything there."""
    return Row(
        CLAIMS[f"fig3.fall_16.{env}"],
        f"{env}, {steps:,} steps",
        None,
        "",
        None,
        f"{steps:,} steps: vanilla PPO learned nothing",
        verdicts.INCONCLUSIVE,
        "a sweep in which vanilla PPO learns: 2M steps on spring (the cpu profile)",
        steps,
    )


def _trained(results: "Fig3Results") -> bool:
    """Whether a Figure 3 sweep learned anything: vanilla's mean return above what an
    agent earns standing still or in place (1000 steps x the healthy reward 1 for the
    Ant; 0 for the HalfCheetah)."""
    vanilla = [r.final_return for r in results.runs if r.cell_types is None]
    return len(vanilla) >= 2 and np.mean(vanilla) > (1000 if results.env == "ant" else 100)


def figure3(ant: "Fig3", cheetah: "Fig3", card: Card) -> dict[str, str]:
    """Figure 3 on both bodies: the sweeps' vanilla numbers (``ant_*``, ``hc_*``), the level
    and fall rows (``level_*``, ``fall_*``, ``cheetah_level_*``, ``cheetah_fall_*``) and the
    typing ablation (``typing_{authors,ours}_*``; "not yet run (fewer than 2 seeds)")."""
    texts = _vanilla("ant", ant) | _vanilla("hc", cheetah)
    texts |= _level_and_fall("", "ant", card) | _level_and_fall("cheetah_", "halfcheetah", card)
    typing = {r.setting.split(",")[0]: r for r in card.get("ch5.typing_explains_fall", [])}
    for who, settings in GENOMES:
        missing = f"{NOT_RUN} (fewer than 2 seeds)"
        texts |= row_texts(f"typing_{settings}", typing.get(who), missing)
    return texts


def _vanilla(prefix: str, payload: "Fig3") -> dict[str, str]:
    """A Figure 3 sweep's steps per run (``{prefix}_steps``, millions), vanilla PPO's mean
    last-two return over its seeds (``_vanilla``), their number (``_vanilla_n``) and that
    mean on the authors' scale (``_vanilla_theirs``)."""
    results = payload.results
    vanilla = [r for r in results.runs if r.cell_types is None]
    steps = trained_steps(payload)
    mean = float(np.mean([r.last_two_return for r in vanilla]))
    return {
        f"{prefix}_steps": f"{steps / 1e6:g}M",
        f"{prefix}_vanilla": f"{mean:.0f}",
        f"{prefix}_vanilla_n": str(len(vanilla)),
        f"{prefix}_vanilla_theirs": f"{authors_scale(results.env, mean):.2f}",
    }


def _level_and_fall(prefix: str, env: str, card: Card) -> dict[str, str]:
    """Figure 3's level at 128 types, fall to 16 types and the fall's shape on ``env``,
    per genome settings (``{prefix}level_ours_*``, ``{prefix}shape_ours_*``, ...), each
    with ``_power``: the power to detect its claim's effect (0.3 of vanilla for the level
    and the fall, the paper's reading of "falls off quickly")."""
    texts = {}
    for who, settings in GENOMES:
        for what, key in FIG3_KEYS.items():
            row = row_of(card, f"{key}.{env}", who)
            name = f"{prefix}{what}_{settings}"
            texts |= row_texts(name, row)
            effect = 0.3 if what != "shape" else CLAIMS[f"{key}.{env}"].paper_effect
            power = None if row is None or row.test is None else stats.power_at(row.test, effect)
            texts[f"{name}_power"] = NOT_RUN if power is None else f"{power:.0%}"
    return texts


def evidence(records: Records) -> list[Row]:
    """Figure 3's rows on each body (the typing ablation on the Ant's), or the row that
    says the sweep learned nothing."""
    rows = []
    for env in ("ant", "halfcheetah"):
        payload = records.get("fig3", env)
        if payload is None:
            continue
        steps = trained_steps(payload)
        if not _trained(payload.results):
            rows.append(untrained_row(env, steps))
            continue
        on_scale = functools.partial(authors_scale, env)
        rows += figure3_rows(payload.results.runs, env, steps, on_authors_scale=on_scale)
        if env == "ant":
            rows += typing_rows(payload.results.runs, steps)
    return rows


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 5 glues of Figure 3's sweeps (``figure3``)."""
    return figure3(records("fig3", "ant"), records("fig3", "halfcheetah"), card)


def fig3_summary(payload: "Fig3") -> list["Fig3Summary"]:
    """A Figure 3 sweep's summary rows (one per settings and cell types), scored by the
    mean of the last two evaluations where the file has that score, else by the last."""
    results = payload.results
    return results.summary if results.summary_last_two is None else results.summary_last_two


def fig3_seeds(payload: "Fig3") -> list[dict]:
    """Each SGB run of a Figure 3 sweep as a fraction of the mean vanilla return, scored as
    ``fig3_summary`` scores it (the mean of the last two evaluations where the file has that
    summary): settings, cell types, seed and fraction; their means are the summary's."""
    results = payload.results
    last_two = results.summary_last_two is not None
    vanilla = next(r.mean_return for r in fig3_summary(payload) if r.cell_types is None)
    return [
        {
            "settings": r.settings,
            "cell_types": r.cell_types,
            "seed": r.seed,
            "fraction": (r.last_two_return if last_two else r.final_return) / vanilla,
        }
        for r in results.runs
        if r.cell_types is not None
    ]


FIG3_COLUMNS = {
    "env": "body",
    "settings": "genome",
    "cell_types": "cell types",
    "mean_return": "mean return",
    "sem_return": "SEM of return",
    "fraction": "fraction of vanilla",
    "sem_fraction": "SEM of fraction",
    "n_seeds": "seeds",
}


FIG3_GENOMES = {
    "ours": "ours",
    "authors": "the authors'",
    "ours_typed_inputs": "ours, inputs typed",
    "authors_untyped_inputs": "the authors', inputs untyped",
}


def fig3_table(payloads: list["Fig3"]) -> pd.DataFrame:
    """Figure 3 sweeps, one row per body, genome settings (``FIG3_GENOMES``) and cell types
    ("vanilla" for PPO), each run scored as the verdicts score it (``fig3_summary``: the
    mean of its last two evaluations where the file has it); columns named as
    ``FIG3_COLUMNS`` maps the files' keys."""
    tables = []
    for payload in payloads:
        summary = [row.model_dump() for row in fig3_summary(payload)]
        table = pd.DataFrame(summary).assign(env=payload.results.env)
        tables.append(table)
    table = pd.concat(tables, ignore_index=True)
    table["cell_types"] = ["vanilla" if pd.isna(k) else f"{k:.0f}" for k in table["cell_types"]]
    table["settings"] = [FIG3_GENOMES.get(s, s) for s in table["settings"]]
    return table[list(FIG3_COLUMNS)].rename(columns=FIG3_COLUMNS)


class Fig3Summary(Record):
    settings: str
    cell_types: Count | None
    mean_return: Return
    sem_return: NonNegative | None
    fraction: Finite | None
    sem_fraction: NonNegative | None
    n_seeds: Count


class Fig3Run(Training):
    settings: str


class Fig3Results(Record):
    env: str
    runs: List[Fig3Run]
    summary: List[Fig3Summary]
    summary_last_two: List[Fig3Summary] = None


class Fig3(ResultsFile):
    provenance: PpoProvenance
    results: Fig3Results
