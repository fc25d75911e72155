"""Chapter 6 figures: evolution without gradients (``sgb.experiments.evolution``),
bet-hedging (``sgb.experiments.bet_hedging``) and fine-tuning from an innate start
(``sgb.experiments.innate_start_supervised``), each drawn from its results file's record."""

from collections.abc import Sequence

import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.axes import Axes

from sgb.plots import PALETTE, WIDTH, axes_or_new
from sgb.schemas import Record
from sgb.stats import sem

_POPULATIONS = (("individuals", PALETTE["individuals"]), ("clones", PALETTE["mean_network"]))


def plot_evolution(results: Record, axes: Sequence[Axes] | None = None) -> list:
    """``results``: an ``EvolutionResults`` record. Two panels. Left: fitness (training
    accuracy of the candidates' networks, %) per generation, mean over seeds, per spread
    sigma (0 the deterministic genome). Right: per sigma, the test accuracy (%) of the
    evolved genome's individuals (their mean; bars, mean over seeds with SEM error bars,
    each seed a dot) and of its mean network (a black tick). Returns the axes."""
    curves, bars = axes_or_new(axes, 1, 2, figsize=(WIDTH, 4.4))
    records = results.records
    sigmas = sorted({r.sigma for r in records})
    colors = sns.color_palette("viridis", len(sigmas))
    for j, sigma in enumerate(sigmas):
        cells = [r for r in records if r.sigma == sigma]
        label = "sigma 0 (deterministic)" if sigma == 0 else f"sigma {sigma:g}"
        fitness = 100 * np.mean([c.mean_fitness for c in cells], axis=0)
        curves.plot(fitness, color=colors[j], lw=1.2, label=label)
        accuracy = [100 * np.mean(c.individuals) for c in cells]
        error = sem(np.asarray(accuracy)) if len(accuracy) > 1 else 0.0
        bars.bar(j, np.mean(accuracy), 0.7, yerr=error, capsize=3, color=colors[j], alpha=0.75)
        bars.plot(np.full(len(accuracy), j), accuracy, "k.", ms=4)
        mean_network = 100 * np.mean([c.mean_network for c in cells])
        bars.plot(j, mean_network, "k_", ms=18, mew=2, label="mean network" if j == 0 else None)
    curves.set_xlabel("generation")
    curves.set_ylabel("fitness: innate training accuracy (%)")
    curves.legend(fontsize=8)
    bars.set_xticks(range(len(sigmas)), [f"{s:g}" for s in sigmas])
    bars.set_xlabel("sigma, held fixed")
    bars.set_ylabel("innate test accuracy (%)")
    bars.legend(fontsize=8, loc="lower right")
    return [curves, bars]


def plot_variance_course(results: Record, ax: Axes | None = None) -> Axes:
    """``results``: an ``EvolutionResults`` record whose runs were scored along the way.
    Per spread sigma > 0, the SD between the evolved genome's individuals (test-accuracy
    points, from the crossed variance split; 0 where every individual scores alike) at
    each scoring: the median over seeds as a line, each seed a dot, hollow where the
    F-test finds no difference (p >= 0.05). Returns the axes."""
    ax = axes_or_new(ax)
    records = [r for r in results.records if r.sigma > 0 and r.course]
    sigmas = sorted({r.sigma for r in records})
    colors = sns.color_palette("viridis", len(sigmas) + 1)[1:]  # sigma 0's colour left out
    for sigma, color in zip(sigmas, colors, strict=True):
        cells = [r for r in records if r.sigma == sigma]
        generations = [p.generation for p in cells[0].course]
        sds = np.array(
            [
                [
                    0.0 if p.variance_split is None else 100 * p.variance_split.between_sd
                    for p in c.course
                ]
                for c in cells
            ]
        )
        ax.plot(generations, np.median(sds, axis=0), color=color, lw=1.5, label=f"sigma {sigma:g}")
        for c, row in zip(cells, sds, strict=True):
            differ = [p.variance_split is not None and p.variance_split.p < 0.05 for p in c.course]
            ax.scatter(
                generations,
                row,
                s=12,
                color=[color if d else "none" for d in differ],
                edgecolors=color,
                lw=0.8,
            )
    ax.set_xlabel("generation")
    ax.set_ylabel("SD between individuals (accuracy points)")
    ax.legend(fontsize=8, title="median over seeds; hollow: p >= 0.05", title_fontsize=8)
    return ax


def plot_hedging(
    results: Record, q: str = "0.5", k: str = "1", axes: Sequence[Axes] | None = None
) -> list:
    """``results``: a ``BetHedgingResults`` record. Two panels, bars per initial spread and
    one for the deterministic lineage: the geometric-mean fitness of the individuals, of
    the clones and of the lineage's members (the mean network at home = 1), and the chance
    that at least ``k`` members survive and survive their retest (a return of ``q`` of the
    mean network's at home, twice); means over genomes with SEM error bars, each genome a
    dot. Returns the axes."""
    fitness, survival = axes_or_new(axes, 1, 2, figsize=(WIDTH, 3.6))
    genomes = results.genomes
    spreads = list(dict.fromkeys(g.rho_init for g in genomes))
    width = 0.8 / len(_POPULATIONS)
    labels = []
    for j, rho in enumerate(spreads):
        group = [g for g in genomes if g.rho_init == rho]
        sigma = np.mean([g.sigma_trained for g in group])
        lineage = all(g.scores.clones is None for g in group)  # no clones: one network
        labels.append(
            f"lineage\n($\\sigma$ {sigma:.0e})"
            if lineage
            else f"$\\rho$ from {rho:g}\n($\\sigma$ {sigma:.2g})"
        )
        bars = [("lineage", "#555555")] if lineage else _POPULATIONS
        for i, (population, color) in enumerate(bars):
            scores = [getattr(g.scores, "individuals" if lineage else population) for g in group]
            x = j if lineage else j + (i - 0.5) * width
            label = population if j == 0 or lineage else None
            _bar(fitness, x, [s.geometric_fitness for s in scores], width, color, label)
            _bar(survival, x, [s.p_retested[q][k] for s in scores], width, color, label)
    for ax in (fitness, survival):
        ax.set_xticks(range(len(spreads)), labels)
        ax.legend(fontsize=8)
    fitness.set_ylabel("geometric-mean fitness")
    fitness.axhline(1.0, color="k", lw=0.6, ls=":")
    survival.set_ylabel(
        f"P(at least {k} survive, retested)\nreturn $\\geq$ {q} x the mean network's at home"
    )
    survival.set_ylim(0, 1.05)
    return [fitness, survival]


def _bar(ax: Axes, x: float, values: list, width: float, color: str, label: str | None) -> None:
    error = sem(np.asarray(values, dtype=float)) if len(values) > 1 else 0.0
    ax.bar(x, np.mean(values), width, yerr=error, capsize=2, color=color, alpha=0.75, label=label)
    ax.plot(np.full(len(values), x), values, "k.", ms=3)


def plot_condition_returns(genome: Record, ax: Axes | None = None) -> Axes:
    """One genome (a ``HedgingGenome`` record): per condition, each member's mean return over
    its episodes, individuals beside clones of the mean network (box plots, each member a
    dot). Returns ``ax``."""
    ax = axes_or_new(ax, figsize=(WIDTH, 3.6))
    populations = {"individuals": genome.returns.individuals, "clones": genome.returns.clones}
    rows = [
        {"condition": condition.replace("_", " "), "population": population, "return": value}
        for population, _ in _POPULATIONS
        for condition, returns in (populations[population] or {}).items()
        for value in np.mean(returns, axis=1)
    ]
    frame = pd.DataFrame(rows)
    style = {"x": "condition", "y": "return", "hue": "population", "ax": ax}
    sns.boxplot(
        frame, **style, palette=dict(_POPULATIONS), showfliers=False, boxprops={"alpha": 0.6}
    )
    sns.stripplot(frame, **style, dodge=True, palette=["k"] * 2, size=2, alpha=0.4, legend=False)
    ax.set(xlabel=None, ylabel="mean return of a member")
    ax.set_title(f"$\\rho$ from {genome.rho_init:g}, seed {genome.training_seed}")
    ax.legend(fontsize=8)
    return ax


def plot_finetune_curves(summary: Sequence[Record], ax: Axes | None = None) -> Axes:
    """Test accuracy (%) against fine-tuning steps, one line per start of ``summary`` (the
    ``CurveSummary`` records of ``sgb.experiments.innate_start_supervised``: mean over seeds,
    with a band of +- SEM where there are several). Returns ``ax``."""
    ax = axes_or_new(ax, figsize=(6.0, 3.6))
    colors = {"individual": PALETTE["individuals"], "mean": PALETTE["mean_network"]}
    for row in summary:
        steps, mean = np.asarray(row.steps), 100 * np.asarray(row.accuracy, dtype=float)
        color = colors.get(row.start, PALETTE["baseline"])
        ax.plot(steps, mean, "o-", color=color, label=f"from {row.start}")
        band = 100 * np.asarray([np.nan if s is None else s for s in row.accuracy_sem])
        ax.fill_between(steps, mean - band, mean + band, color=color, alpha=0.2)
    ax.set_xlabel("steps of learning the new task")
    ax.set_xscale("symlog", linthresh=10)
    ax.set_ylabel("test accuracy (%)")
    ax.legend(fontsize=8)
    return ax
