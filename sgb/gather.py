"""The scorecard's rows, gathered from every experiment's evidence.

Each experiment that judges a claim has ``evidence(records) -> list[Row]`` in its module
(``sgb.experiments.EXPERIMENTS``: its ``evidence``); ``EVIDENCE`` is their order on the
scorecard, and the claims no run here can test follow them (``UNTESTABLE``). A results
file missing from the results directory leaves its rows out; a damaged one is refused
(``sgb.results.load``: a ``CorruptFile`` naming it).
"""

from pathlib import Path

from sgb import schemas
from sgb.claims import Row, untestable
from sgb.experiments import EXPERIMENTS, results_files
from sgb.results import Records, Source

# the experiments whose evidence makes the scorecard's rows, in its order
EVIDENCE = (
    "fig2",
    "sgb_full",
    "width",
    "fig3",
    "regime",
    "fig4",
    "fig5",
    "populations",
    "regime_populations",
    "theory",
    "saddle",
    "evolution",
    "bet_hedging",
    "innate_start",
    "innate_start_supervised",
)
# the benchmarks' results (``benchmarks/``), read beside the experiments'
BENCHMARKS = {
    "bench_backends": Source({"": "rl/bench_backends.json"}, schemas.BenchBackends),
    "bench_rl": Source({"": "rl/bench_rl.json"}, schemas.BenchRl),
    "bench_regime": Source({"": "rl/bench_regime.json"}, schemas.BenchRegime),
    "bench_parallel": Source({"": "bench_parallel.json"}, schemas.BenchParallel),
}
# claim key -> why no run here can test it
UNTESTABLE = {
    "fig4f.r_terrain": "ANYmal on terrain needs Isaac Gym and a GPU; Brax's spring backend "
    "has no height fields (chapter 5 measures two physical niches instead)",
    "fig2.cifar": "CIFAR-10 needs the internet to download; its loader is tested on written files",
}


def sources() -> dict[str, Source]:
    """Every experiment's and benchmark's results files and their model."""
    return {name: Source(*found) for name, found in results_files().items()} | BENCHMARKS


def records(results_dir: str | Path | None = None) -> Records:
    """The results under ``results_dir`` (default: the committed ones), read by experiment."""
    return Records(sources(), results_dir)


def model_of(name: str) -> type[schemas.ResultsFile]:
    """The model of the results file ``name`` (its path under the results directory, as an
    experiment or benchmark declares it); a ValueError naming it where none does."""
    found = [s.model for s in sources().values() if name in s.files.values()]
    if not found:
        raise ValueError(
            f"no experiment or benchmark declares the results file {name} "
            "(sgb.experiments.EXPERIMENTS' results, sgb.gather.BENCHMARKS)"
        )
    return found[0]


def scorecard(results_dir: str | Path | None = None) -> list[Row]:
    """Every row the results under ``results_dir`` (default: the committed ones) give, in
    the order of ``EVIDENCE``, then the claims no run here can test."""
    found = records(results_dir)
    rows = [row for name in EVIDENCE for row in EXPERIMENTS[name].evidence(found)]
    return rows + [untestable(key, reason) for key, reason in UNTESTABLE.items()]
