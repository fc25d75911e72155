"""Figures of chapters 1 and 2: the bottleneck, compression by cell types, Bayes by backprop."""

from collections.abc import Mapping, Sequence

import numpy as np
from scipy import stats as scipy_stats

from sgb.plots import PALETTE, WIDTH, axes_or_new
from sgb.stats import sem


def bits_bars(bits: Mapping[str, float], title: str, ax=None):
    """Horizontal bars of information amounts (bits) on a log axis."""
    ax = axes_or_new(ax, figsize=(6.5, 0.6 + 0.5 * len(bits)))
    names = list(bits)
    ax.barh(names, [bits[n] for n in names], color=PALETTE["sgb"])
    ax.set_xscale("log")
    ax.set_xlim(min(bits.values()) / 10, max(bits.values()) * 30)
    ax.set_xlabel("information (bits, log scale)")
    ax.set_title(title)
    ax.invert_yaxis()
    for i, name in enumerate(names):
        ax.text(bits[name], i, f" {bits[name]:.1e}", va="center", fontsize=9)
    return ax


def compression_curves(curves: Mapping[str, tuple[Sequence[int], Sequence[float]]], ax=None):
    """Compression ratio against the number of hidden cell types, one line per network."""
    ax = axes_or_new(ax)
    for name, (types, ratios) in curves.items():
        ax.plot(types, ratios, marker="o", label=name)
    ax.axhline(1.0, color=PALETTE["baseline"], lw=1, ls="--", label="no compression")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("cell types per hidden layer, k")
    ax.set_ylabel("compression ratio (dense params / SGB params)")
    ax.legend(loc="upper right", fontsize=8)
    return ax


def predictive_bands(fit: Mapping[str, np.ndarray], ax=None):
    """Training data, the predictive mean and +-1, 2 standard deviations of a Bayesian MLP."""
    ax = axes_or_new(ax)
    grid, mean, std = fit["grid"], fit["mean"], fit["std"]
    for k, alpha in ((2, 0.15), (1, 0.3)):
        ax.fill_between(
            grid,
            mean - k * std,
            mean + k * std,
            color=PALETTE["sgb"],
            alpha=alpha,
            lw=0,
            label=f"mean $\\pm$ {k} sd",
        )
    ax.plot(grid, mean, color=PALETTE["sgb"], label="predictive mean")
    ax.plot(grid, np.sin(3 * grid), color=PALETTE["baseline"], ls="--", lw=1, label="sin(3x)")
    ax.scatter(fit["x"], fit["y"], s=12, color="black", zorder=3, label="training data")
    ax.set_xlabel("input x")
    ax.set_ylabel("output y")
    ax.legend(loc="lower left", fontsize=8)
    return ax


def accuracy_comparison(rows: Sequence[Mapping], ax=None):
    """Innate test accuracy (%) per classifier: mean network, individuals and the
    population-averaged prediction, each a point at its mean over the sampled individuals
    and seeds with its 95 % interval (a t interval; none for a single value). Points, not
    bars, so the axis need not start at 0 to show the differences; the legend sits below
    the axes, off the data."""
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    kinds = [
        ("mean_network", "mean network"),
        ("individuals", "sampled individuals"),
        ("population_average", "population-averaged prediction"),
    ]
    colors = [PALETTE["mean_network"], PALETTE["individuals"], PALETTE["sgb"]]
    ax = axes_or_new(ax, figsize=(WIDTH, 4))
    offset = 0.2
    for j, ((key, label), color) in enumerate(zip(kinds, colors, strict=True)):
        means, errors = [], []
        for variant in variants:
            values = 100 * np.concatenate(
                [np.atleast_1d(r[key]) for r in rows if r["variant"] == variant]
            )
            means.append(values.mean())
            half = scipy_stats.t.ppf(0.975, values.size - 1) * sem(values) if values.size > 1 else 0
            errors.append(half)
        x = np.arange(len(variants)) + (j - 1) * offset
        ax.errorbar(x, means, yerr=errors, fmt="o", capsize=3, color=color, label=label)
    ax.set_xticks(np.arange(len(variants)), variants, fontsize=9)
    ax.set_ylabel("test accuracy (%)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3, fontsize=9, frameon=False)
    return ax


def type_pair_histogram(weights: np.ndarray, mu: float, sigma: float, title: str, ax=None):
    """Histogram of one type pair's sampled weights against its N(mu, sigma^2) density."""
    ax = axes_or_new(ax)
    ax.hist(
        weights,
        bins=30,
        density=True,
        color=PALETTE["individuals"],
        alpha=0.7,
        label=f"{weights.size} sampled synapses",
    )
    grid = np.linspace(mu - 4 * sigma, mu + 4 * sigma, 200)
    ax.plot(
        grid,
        scipy_stats.norm.pdf(grid, mu, sigma),
        color="black",
        label=f"N($\\mu$={mu:.3f}, $\\sigma$={sigma:.3f})",
    )
    ax.set_xlabel("synaptic weight")
    ax.set_ylabel("density")
    ax.set_title(title)
    ax.legend(fontsize=8)
    return ax
