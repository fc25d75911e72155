"""Every figure fits the book's content column with its text at least 8 pt as shown:
the figure functions drawn on small synthetic data, and every figure size and font size
written in the package's figures and the chapters read at the source."""

import json
import re
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from sgb.experiments import evolution, rl_spread
from sgb.experiments.bet_hedging import BetHedgingResults, HedgingGenome
from sgb.experiments.evolution import EvolutionResults
from sgb.experiments.theory import FixedPoint
from sgb.plots import (
    COLUMN_IN,
    MIN_FONT_PT,
    WIDTH,
    apply_style,
    beyond,
    rl,
    shown_min_font_pt,
    shown_width_in,
    subplots,
    theory,
    wiring,
)
from sgb.schemas import BenchBackendsResults, Training

matplotlib.use("agg")

ROOT = Path(__file__).resolve().parents[1]
LOSSES = ("convex", "concave", "nonconvex")


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    matplotlib.pyplot.close("all")


def test_shown_size_shrinks_the_text_of_a_figure_wider_than_the_column():
    fig, ax = subplots(figsize=(2 * COLUMN_IN, 3))
    ax.text(0.5, 0.5, "wide", fontsize=10)
    ax.tick_params(labelsize=12)
    assert shown_width_in(fig) == pytest.approx(2 * COLUMN_IN, abs=0.3)
    assert shown_min_font_pt(fig) == pytest.approx(10 * COLUMN_IN / shown_width_in(fig))
    assert shown_min_font_pt(fig) < 5.5
    fig, ax = subplots(figsize=(4, 3))
    ax.text(0.5, 0.5, "narrow", fontsize=9)
    assert shown_min_font_pt(fig) == 9


def test_the_theme_writes_text_of_at_least_8_pt():
    apply_style()
    rc = matplotlib.rcParams
    for key in ("xtick.labelsize", "ytick.labelsize", "legend.fontsize", "axes.labelsize"):
        assert matplotlib.font_manager.FontProperties(size=rc[key]).get_size() >= MIN_FONT_PT
    assert rc["figure.figsize"][0] <= COLUMN_IN


def _theory_results(rng) -> dict:
    steps, scales = 30, [0.5, 1.0, 2.0]
    curve = {
        name: {
            k: rng.normal(size=steps) for k in ("mu", "gap", "gap_stderr", "prediction", "sigma")
        }
        for name in LOSSES
    }
    for run in curve.values():
        run["sigma"], run["gap_stderr"] = np.abs(run["sigma"]), np.abs(run["gap_stderr"])
    mu0 = np.linspace(-2, 2, 5)
    scan = {
        name: {
            "mu0": mu0,
            "sigma0": 0.5,
            **{f"gap_{s}": rng.normal(size=5) for s in ("start", "end")},
            **{f"gap_stderr_{s}": np.full(5, 0.1) for s in ("start", "end")},
        }
        for name in LOSSES
    }
    sigma = np.linspace(0.1, 1.0, 4)
    rows = [
        {"mu": m, "curvature": 1.0, "measured": sigma, "stderr": sigma / 10}
        | {"exact": sigma, "predicted": sigma}
        for m in (-1.0, 0.0, 1.0)
    ]
    gap = {"gap": 0.1, "stderr": 0.01}
    network = [
        {
            "cell_types": types,
            "scales": [
                {"scale": c, "predicted": 0.1, "train_cross_entropy": gap}
                | {"train_error_rate": gap, "test_error_rate": gap}
                for c in scales
            ],
        }
        for types in ((None, 8, 10), (4, 4, 10))
    ]
    sigma_runs = np.abs(rng.normal(size=(3, steps)))
    return {
        "trajectories": curve,
        "sign_scan": scan,
        "sign_map": {
            "mu0": mu0,
            "sigma0": np.linspace(0.1, 1, 3),
            "gap_start": rng.normal(size=(5, 3)),
            "gap_end": rng.normal(size=(5, 3)),
            "gap_stderr_end": np.full((5, 3), 0.1),
        },
        "breakdown": {"sigma": sigma, "rows": rows},
        "network": network,
        "elbo_toy": {
            "steps": np.arange(steps),
            "kl_weights": np.array([0.0, 0.1, 1.0]),
            "predicted_sigma": np.array([0.0, 0.3, 0.7]),
            "runs": {"softplus": {"sigma": sigma_runs}, "sigma": {"sigma": sigma_runs}},
            "prior_sigma": 1.0,
            "learning_rate": 0.1,
        },
    }


RNG = np.random.default_rng(0)
MU, SIGMA = RNG.normal(size=(3, 2)), np.abs(RNG.normal(size=(3, 2)))
THEORY = _theory_results(RNG)
SPREAD = [
    rl_spread.SpreadSummary.model_validate(
        {"rho_init": float(np.log(np.expm1(s))), "sigma_init": s, "sigma_trained": s}
        | {"advantage": 1.0, "sem_advantage": 0.1, "mean_network_mean": 1e3, "n_seeds": 3}
        | {"individuals_sd": 2.0, "sem_individuals_sd": 0.2}
    )
    for s in (0.01, 0.1, 1.0)
]
SPEED = {"train_steps_per_s": 1e4, "wall_time_s": 10.0}
BENCH = BenchBackendsResults.model_validate(
    {
        "env": "halfcheetah",
        "throughput_steps": 100_000,
        "throughput": {b: SPEED for b in ("spring", "mjx")},
        "reach": {"backend": "mjx", "eval_steps": [0, 1_000_000], "eval_returns": [0.0, 1e3]}
        | SPEED,
    }
)
SUMMARY = {"median_ratio": 0.95, "log_correlation": 0.91, "ratio_q10": 0.5, "ratio_q90": 2.0}
LAYER = {
    k: np.abs(RNG.normal(size=12)).tolist() for k in ("sigma2", "curvature", "curvature_population")
}
FIXED = [
    FixedPoint.model_validate(
        {
            "cell_types": types,
            "runs": [
                {"epochs": e, "kl_weight": 1e-3, "prior_sigma": 1.0, "sigma2_init": 0.01}
                | {"population_hessians": 8}
                | {"accuracy": {"mean_network": 0.9, "population_average": 0.8}}
                | {"layers": {"dense": LAYER}}
                | {"summary": {"at_mean": SUMMARY, "population": SUMMARY}}
                for e in (3, 30, 300)
            ],
        }
    )
    for types in ([None, 8, 10], [4, 4, 10])
]
RETURNS = {"normal": {k: RNG.normal(size=(20, 3)) for k in ("individuals", "mean_network")}}
CONDITIONS = ("normal", "long_legs", "slippery", "low_gravity")
P_SURVIVE = {"0.5": {"1": 0.9, "10": 0.5, "50": 0.1}}
SCORE = {
    "geometric_fitness": 1.0,
    "mean_fitness": 1.0,
    "p_at_least": P_SURVIVE,
    "p_retested": P_SURVIVE,
}
GENOME = HedgingGenome.model_validate(
    {
        "returns": {
            p: {c: RNG.normal(1e3, 200, size=(30, 4)).tolist() for c in CONDITIONS}
            for p in ("individuals", "clones")
        },
        "rho_init": -3.0,
        "training_seed": 0,
        "sigma_trained": 0.1,
        "scale": 1e3,
        "scores": {"individuals": SCORE, "clones": SCORE},
    }
)
LINEAGE = GENOME.model_dump() | {"rho_init": -30.0, "sigma_trained": 1e-13}
LINEAGE["returns"]["clones"] = LINEAGE["scores"]["clones"] = None
HEDGING = BetHedgingResults.model_validate(
    {
        "genomes": [
            *(GENOME.model_dump() | {"training_seed": s} for s in range(3)),
            *(LINEAGE | {"training_seed": s} for s in range(3)),
        ]
    }
)
EVOLVED_CELLS = [
    {
        "hidden_types": 8,
        "sigma": sigma,
        "seed": seed,
        "compression": 5.0,
        "mean_fitness": np.linspace(0.1, 0.8, 100).tolist(),
        "individuals": RNG.uniform(0.7, 0.9, 20).tolist(),
        "mean_network": 0.8,
        "wall_time_s": 1.0,
    }
    for sigma in (0.0, 0.15, 0.5, 1.5)
    for seed in range(3)
]
EVOLVED = EvolutionResults.model_validate(
    {
        "dataset": "digits",
        "records": EVOLVED_CELLS,
        "convergence": [evolution.convergence(c) for c in EVOLVED_CELLS],
    }
)
FRAMES = {name: np.zeros((40, 60, 3)) for name in ("normal", "long legs", "slippery")}
REGIME_RUNS = [
    Training.model_validate(
        {"cell_types": k, "seed": seed, "final_return": r, "last_two_return": r}
        | {"eval_steps": [0, 10**6, 2 * 10**6], "eval_returns": [-500.0, r / 2, r]}
    )
    for k, r in ((None, 7e3), (128, 7e3), (64, 5e3), (32, 3e3), (16, 500.0))
    for seed in range(3)
]

# each figure function on synthetic data of its shape, drawn in its test
FIGURES = {
    "wiring.model_schematic": lambda: wiring.model_schematic(MU, SIGMA, RNG.normal(size=(3, 6, 4))),
    "wiring.expansion": lambda: wiring.expansion(MU, (10, 7)),
    "wiring.individuals": lambda: wiring.individuals(RNG.normal(size=(4, 10, 7)), (3, 2)),
    **{
        f"theory.{name}": lambda name=name: getattr(theory, name)(THEORY)
        for name in ("figure6", "sign_scan", "sign_map", "breakdown", "network_gap", "elbo_toy")
    },
    "theory.fixed_point": lambda: theory.fixed_point(FIXED),
    "beyond.plot_condition_returns": lambda: beyond.plot_condition_returns(GENOME),
    "beyond.plot_hedging": lambda: beyond.plot_hedging(HEDGING),
    "beyond.plot_evolution": lambda: beyond.plot_evolution(EVOLVED),
    "rl.plot_spread": lambda: rl.plot_spread(SPREAD),
    "rl.plot_regime": lambda: rl.plot_regime(REGIME_RUNS),
    "rl.plot_regime_sweep": lambda: rl.plot_regime_sweep(REGIME_RUNS),
    "rl.plot_backends": lambda: rl.plot_backends(BENCH),
    "rl.plot_mean_network": lambda: rl.plot_mean_network(
        RETURNS["normal"]["individuals"], RETURNS["normal"]["mean_network"]
    ),
    "rl.show_images": lambda: rl.show_images(FRAMES),
}


@pytest.mark.parametrize("name", FIGURES)
def test_every_figure_fits_the_column_with_text_of_at_least_8_pt(name):
    fig = np.ravel(FIGURES[name]())[0].figure
    assert fig.get_figwidth() <= WIDTH
    assert shown_width_in(fig) <= COLUMN_IN
    assert shown_min_font_pt(fig) >= MIN_FONT_PT


def _sources() -> dict[str, str]:
    """Every figure module's source and every chapter's code, by name."""
    sources = {p.name: p.read_text() for p in sorted((ROOT / "sgb" / "plots").glob("*.py"))}
    for chapter in sorted((ROOT / "book").glob("*.ipynb")):
        cells = json.loads(chapter.read_text())["cells"]
        code = [c["source"] for c in cells if c["cell_type"] == "code"]
        sources[chapter.name] = "\n".join("".join(s) if isinstance(s, list) else s for s in code)
    return sources


def test_every_figure_size_and_font_size_written_fits():
    """A figure is at most ``WIDTH`` wide (the name or a literal), whatever its
    panels; every font size written is at least 8 pt."""
    widths, sizes = 0, 0
    for name, source in _sources().items():
        for width in re.findall(r"figsize=\(\s*([^,]+),", source):
            widths += 1
            assert width.strip() == "WIDTH" or float(width) <= WIDTH, (name, width)
        for size in re.findall(r"\b(?:fontsize|labelsize)=([\d.]+)", source):
            sizes += 1
            assert float(size) >= MIN_FONT_PT, (name, size)
    assert widths >= 20 and sizes >= 20  # the figures were found, not an empty loop
