"""What each chapter glues into its prose from the committed results: one table, chapter
-> its texts (glue name -> text), read by the chapter itself and by its test.

    book.glue_all(chapters.texts("05_brax_populations", RESULTS))

A chapter glues a few more values it computes while it runs (``COMPUTED``); every other
``{glue}`` name of its prose is a key of ``texts``.
"""

import functools
from collections.abc import Callable
from pathlib import Path

from sgb import claims, prose
from sgb.experiments import rl_spread
from sgb.paths import committed_results
from sgb.results import load as load_results

Loader = Callable[..., dict | None]  # results.load with the results directory bound


def _jensen_gap(load: Loader, card: prose.Card) -> dict[str, str]:
    return prose.descent(card)


def _dgb_vs_sgb(load: Loader, card: prose.Card) -> dict[str, str]:
    fashion = load("fig2_fashion-mnist_cpu.json")["results"]
    dense = fashion["ours"]["summary"]["dense"]["mean"][0]
    return (
        prose.figure2(fashion, card)
        | prose.mean_gap(load("mean_gap_fashion-mnist_cpu.json")["results"])
        | prose.dgb_budget(load("dgb_budget_fashion-mnist_cpu.json")["results"], dense)
        | prose.sgb_full(load("sgb_full_fashion-mnist_cpu.json"))
        | prose.figure2_full(load("dgb_full_fashion-mnist_cpu.json"), card)
        | prose.supervised_population(card)
        | prose.kl_share(card)
    )


def _brax_populations(load: Loader, card: prose.Card) -> dict[str, str]:
    fig3 = [load(f"rl/fig3_{env}_cpu.json") for env in ("ant", "halfcheetah")]
    return (
        prose.backends(load("rl/bench_backends.json"))
        | prose.regime(load("rl/regime_ant_cpu.json"))
        | prose.regime_peer(load("rl/regime_peer_ant_cpu.json", missing_ok=True))
        | prose.regime_gait(load("rl/regime_gait_ant_cpu.json", missing_ok=True))
        | prose.regime_populations(load("rl/regime_populations_ant_cpu.json", missing_ok=True))
        | prose.populations(load("rl/populations_ant_cpu.json"))
        | prose.figure3(*fig3, card)
        | prose.figures4_5(card)
        | prose.variability(card)
        | rl_spread.spread_prose(load("rl/spread_ant_cpu.json")["results"]["runs"])
    )


def _beyond_the_paper(load: Loader, card: prose.Card) -> dict[str, str]:
    return (
        prose.evolution(load("evolution_digits_cpu.json"))
        | prose.bet_hedging(load("rl/bet_hedging_ant_cpu.json", missing_ok=True))
        | prose.innate_start(
            load("rl/innate_start_ant_cpu.json", missing_ok=True),
            load("innate_start_supervised_fashion-mnist_cpu.json", missing_ok=True),
        )
    )


# chapter (its notebook's stem) -> its texts from the results and the scorecard's rows
CHAPTERS: dict[str, Callable[[Loader, prose.Card], dict[str, str]]] = {
    "03_jensen_gap": _jensen_gap,
    "04_dgb_vs_sgb": _dgb_vs_sgb,
    "05_brax_populations": _brax_populations,
    "06_beyond_the_paper": _beyond_the_paper,
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
    results_dir = committed_results() if results_dir is None else Path(results_dir)
    if card is None:
        card = claims.by_key(claims.scorecard(results_dir))
    return CHAPTERS[chapter](functools.partial(load_results, results_dir=results_dir), card)
