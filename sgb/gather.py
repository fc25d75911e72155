"""The scorecard's rows, gathered from every experiment's evidence.

Each experiment that judges a claim has ``evidence(records) -> list[Row]`` in its module
(``sgb.experiments.EXPERIMENTS``: its ``evidence``); ``EVIDENCE`` is their order on the
scorecard, and the claims no run here can test follow them (``UNTESTABLE``). A results
file missing from the results directory leaves its rows out; a damaged one is refused
(``sgb.results.load``: a ``CorruptFile`` naming it).
"""

from pathlib import Path

from sgb.claims import Row, untestable
from sgb.experiments import EXPERIMENTS, results_files
from sgb.results import Records

# the experiments whose evidence makes the scorecard's rows, in its order
EVIDENCE = (
    "fig2",
    "sgb_full",
    "fig3",
    "regime",
    "fig4",
    "fig5",
    "populations",
    "regime_populations",
    "theory",
    "evolution",
    "bet_hedging",
    "innate_start",
    "innate_start_supervised",
)
# results read beside the experiments': name -> part -> file (as ``results_files``)
BENCHMARKS = {"bench_backends": {"": "rl/bench_backends.json"}}  # benchmarks/bench_backends.py
# claim key -> why no run here can test it
UNTESTABLE = {
    "fig4f.r_terrain": "ANYmal on terrain needs Isaac Gym and a GPU; Brax's spring backend "
    "has no height fields (chapter 5 measures two physical niches instead)",
    "fig2.cifar": "CIFAR-10 needs the internet to download; its loader is tested on written files",
}


def records(results_dir: str | Path | None = None) -> Records:
    """The results under ``results_dir`` (default: the committed ones), read by experiment."""
    return Records(results_files() | BENCHMARKS, results_dir)


def scorecard(results_dir: str | Path | None = None) -> list[Row]:
    """Every row the results under ``results_dir`` (default: the committed ones) give, in
    the order of ``EVIDENCE``, then the claims no run here can test."""
    found = records(results_dir)
    rows = [row for name in EVIDENCE for row in EXPERIMENTS[name].evidence(found)]
    return rows + [untestable(key, reason) for key, reason in UNTESTABLE.items()]
