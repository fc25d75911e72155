"""How the chapters' prose quotes a result: glue name -> markdown text.

Each experiment's ``texts`` (in its module) returns every name its part of a chapter
glues (``book.glue_all``), built with the pieces here: a scorecard row as texts
(``row_texts``), the row of a claim and setting (``row_of``), a percentage. A scorecard
row missing from ``card`` (its results not yet run) gives ``NOT_RUN`` for each of its
names; a missing results file gives the fallback its function names.
"""

import math
from importlib import metadata

from sgb.claims import Row
from sgb.schemas import BenchBackends, BenchRegime

NOT_RUN = "not yet run"
ROW_PARTS = ("verdict", "ours", "detectable", "decide")
Card = dict[str, list[Row]]  # claims.by_key(rows): claim key -> its rows


def row_texts(name: str, row: Row | None, missing: str = NOT_RUN) -> dict[str, str]:
    """A scorecard row as ``{name}_verdict`` (bold), ``_ours`` (estimate with its 95 %
    interval, "no estimate" without a test), ``_detectable`` (the effect detectable at 80 %
    power, "none" without a test or power) and ``_decide`` (the budget that would decide);
    ``missing`` for each without a row. Words, not a dash, so that prose reads around them."""
    if row is None:
        return {f"{name}_{part}": missing for part in ROW_PARTS}
    detectable = math.nan if row.test is None else row.test.detectable
    return {
        f"{name}_verdict": f"**{row.verdict}**",
        f"{name}_ours": "no estimate" if row.test is None else row.ours,
        f"{name}_detectable": "none" if math.isnan(detectable) else f"{detectable:.3g}",
        f"{name}_decide": row.decide or "nothing more",
    }


def row_of(card: Card, key: str, setting: str = "") -> Row | None:
    """The first row of claim ``key`` whose setting names ``setting``, or ``None``."""
    return next((r for r in card.get(key, []) if setting in r.setting), None)


GENOMES = (("our genome", "ours"), ("the authors' genome", "authors"))


# Chapter 5 --------------------------------------------------------------------------------

REGIME_STEPS = "5 x 10^7 steps"  # the budget a regime population row names


def regime_setting(row: Row) -> str:
    """A regime population row's setting after the regime and its budget where that is the
    paper's: e.g. ``128 types, seed 0, sampled actions``, ``9.83 x 10^6 steps, 64 types,
    seed 0, sampled actions``."""
    setting = row.setting.removeprefix("ant, the authors' regime, ")
    return setting.removeprefix(f"{REGIME_STEPS}, ")


def backends(bench: BenchBackends) -> dict[str, str]:
    """``mjx_vs_spring`` (MJX's training env-steps/s over spring's), ``fastest_backend`` and
    the installed ``brax_version``, from ``benchmarks/bench_backends.py``'s results."""
    speeds = {name: s.train_steps_per_s for name, s in bench.results.throughput.items()}
    return {
        "mjx_vs_spring": f"{speeds['mjx'] / speeds['spring']:.2f}x",
        "fastest_backend": f"`{max(speeds, key=speeds.get)}`",
        "brax_version": metadata.version("brax"),
    }


def evaluation_share(bench: BenchRegime) -> dict[str, str]:
    """``regime_eval_share``: the part of a regime run's CPU time its evaluations take at
    the regime's protocol, per configuration of ``benchmarks/bench_regime.py``'s results."""
    shares = [
        f"{100 * row.evaluation_share:.0f} % "
        + ("(vanilla)" if row.cell_types is None else f"({row.cell_types} types)")
        for row in bench.results.rows
    ]
    return {"regime_eval_share": " and ".join(shares)}


# Chapter 4 --------------------------------------------------------------------------------


def percent(value: float) -> str:
    return f"{100 * value:.1f} %"


# Chapter 6 --------------------------------------------------------------------------------


def mean_sem(mean: float, sem: float, scale: float = 1.0, decimals: int = 0) -> str:
    """``mean ± sem`` as text (``sem`` omitted where NaN: one seed)."""
    if math.isnan(sem):
        return f"{scale * mean:.{decimals}f}"
    return f"{scale * mean:.{decimals}f} ± {scale * sem:.{decimals}f}"
