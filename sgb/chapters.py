"""What each chapter glues into its prose from the results: one table, chapter -> the
experiments whose texts it glues, read by the chapter itself and by its test.

    book.glue_all(chapters.texts("05_brax_populations", RESULTS))

Each experiment's module has ``texts(records, card) -> dict`` (glue name -> text, from its
results and the scorecard's rows). A chapter glues a few more values it computes while
it runs (``COMPUTED``); every other ``{glue}`` name of its prose is a key of ``texts``.
"""

from pathlib import Path

from sgb import claims, gather, prose
from sgb.experiments import EXPERIMENTS
from sgb.results import Records


def _backends(records: Records, card: prose.Card) -> dict[str, str]:
    return prose.backends(records("bench_backends"))


def _bench_regime(records: Records, card: prose.Card) -> dict[str, str]:
    return prose.evaluation_share(records("bench_regime"))


# name -> texts(records, card): each experiment's, and the benchmarks chapter 5 cites
SOURCES = {name: e.texts for name, e in EXPERIMENTS.items() if e.texts} | {
    "bench_backends": _backends,
    "bench_regime": _bench_regime,
}
# chapter (its notebook's stem) -> the sources whose texts it glues
CHAPTERS = {
    "03_jensen_gap": ("theory", "saddle"),
    "04_dgb_vs_sgb": ("fig2", "mean_gap", "dgb_budget", "sgb_full", "width"),
    "05_brax_populations": (
        "bench_backends",
        "bench_regime",
        "regime",
        "regime_peer",
        "regime_gait",
        "populations",
        "fig3",
        "fig4",
        "spread",
    ),
    "06_beyond_the_paper": ("evolution", "bet_hedging", "innate_start"),
}
# names a chapter glues from what it computes while it runs, not from results files
COMPUTED = {
    "03_jensen_gap": frozenset(),
    "04_dgb_vs_sgb": frozenset({"nominal_30_real", "nominal_1500_real"}),
    "05_brax_populations": frozenset({"walk_sigma_narrow", "walk_sigma_wide", "walk_steps"}),
    "06_beyond_the_paper": frozenset(),
}


def texts(
    chapter: str, results_dir: Path | None = None, card: prose.Card | None = None
) -> dict[str, str]:
    """The texts ``chapter`` glues from the results under ``results_dir`` (default: the
    committed ones) and the scorecard's rows ``card`` (computed from them if ``None``)."""
    if chapter not in CHAPTERS:
        raise ValueError(f"no texts for chapter {chapter!r}; chapters: {', '.join(CHAPTERS)}")
    records = gather.records(results_dir)
    if card is None:
        card = claims.by_key(gather.scorecard(results_dir))
    found: dict[str, str] = {}
    for name in CHAPTERS[chapter]:
        found |= SOURCES[name](records, card)
    return found
