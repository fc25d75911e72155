"""Figures of chapter 3 (the Jensen gap), drawn from ``sgb.experiments.theory.compute``
results; the fixed points (``fixed_point``) and the saddle points (``saddle``) from their
records."""

from collections.abc import Sequence
from typing import Any

import jax.numpy as jnp
import numpy as np
from matplotlib.colors import ListedColormap

from sgb import stats, theory
from sgb.plots import PALETTE, WIDTH, axes_or_new, panels
from sgb.schemas import Record

TITLES = {"convex": "convex", "concave": "concave", "nonconvex": "non-convex"}


def _a(x) -> np.ndarray:
    return np.asarray(x, dtype=float)


def types_label(cell_types) -> str:
    """Cell types per layer as "n/8/10" ("n": one type per neuron)."""
    return "/".join("n" if k is None else str(k) for k in cell_types)


def figure6(results: dict[str, Any], axes=None) -> np.ndarray:
    """The paper's Figure 6, one row per toy loss (``axes``: (losses, 2)): the loss curve
    with mu's start (x) and end (triangle) and the population's spread (mu +- sigma), and
    Delta L over training; the legends once, on the first row."""
    runs = results["trajectories"]
    axes = axes_or_new(axes, len(runs), 2, figsize=(WIDTH, 2.8 * len(runs)), squeeze=False)
    for row, (name, run) in enumerate(runs.items()):
        mu, sigma = _a(run["mu"]), _a(run["sigma"])
        lo = min(mu.min() - 2 * sigma.max(), -2.0)
        hi = max(mu.max() + 2 * sigma.max(), 2.0)
        w = np.linspace(lo, hi, 400)
        loss = theory.toy_loss(name)
        top, bottom = axes[row, 0], axes[row, 1]
        top.plot(w, loss(jnp.asarray(w)), color="k", lw=1.5, label="$L(w)$")
        for i, color, marker, label in ((0, "k", "x", "start"), (-1, "red", "^", "end")):
            top.axvspan(
                mu[i] - sigma[i],
                mu[i] + sigma[i],
                color=color,
                alpha=0.12,
                label=f"{label}: $\\mu \\pm \\sigma$",
            )
            top.plot(
                mu[i], loss(mu[i]), marker, color=color, ms=10, mew=2, label=f"{label}: $\\mu$"
            )
        top.set(title=f"{TITLES[name]} loss", xlabel="weight $w$", ylabel="loss $L(w)$")
        if row == 0:
            top.legend(fontsize=8, loc="best")
        steps = np.arange(mu.size)
        gap, se = _a(run["gap"]), _a(run["gap_stderr"])
        bottom.plot(steps, gap, color=PALETTE["sgb"], label=r"measured $\Delta L$")
        bottom.fill_between(steps, gap - 2 * se, gap + 2 * se, color=PALETTE["sgb"], alpha=0.25)
        bottom.plot(
            steps,
            _a(run["prediction"]),
            "--",
            color=PALETTE["dgb"],
            label=r"$\frac{1}{2} L''(\mu)\,\sigma^2$",
        )
        bottom.axhline(0, color="grey", lw=0.8)
        bottom.set(
            xlabel="gradient step",
            ylabel=r"$\Delta L = \mathbb{E}[L(\mu + \sigma\epsilon)] - L(\mu)$",
        )
        if row == 0:
            bottom.legend(fontsize=8)
    return axes


def sign_scan(results: dict[str, Any], axes=None) -> np.ndarray:
    """Delta L before and after training, against the starting mean mu0, for every toy loss."""
    scan = results["sign_scan"]
    axes = panels(axes, len(scan), 2.8)
    for ax, (name, row) in zip(axes, scan.items(), strict=True):
        mu0 = _a(row["mu0"])
        for stage, color in (("start", "k"), ("end", "red")):
            gap, se = _a(row[f"gap_{stage}"]), _a(row[f"gap_stderr_{stage}"])
            ax.errorbar(
                mu0, gap, yerr=2 * se, fmt="o-", ms=3, color=color, label=f"{stage} of training"
            )
        ax.axhline(0, color="grey", lw=0.8)
        ax.set(
            title=f"{TITLES[name]} ($\\sigma_0$ = {row['sigma0']:g})",
            xlabel=r"starting mean $\mu_0$",
            ylabel=r"$\Delta L$",
        )
        ax.set_yscale("symlog", linthresh=1e-4)
        ax.legend(fontsize=8)
    return axes


def sign_map(results: dict[str, Any], axes=None) -> np.ndarray:
    """Non-convex loss: sign of Delta L over the starting point (mu0, sigma0), before and after
    training; grey where |Delta L| < 3 standard errors (not distinguishable from 0)."""
    grid = results["sign_map"]
    mu0, sigma0 = _a(grid["mu0"]), _a(grid["sigma0"])
    start = np.sign(_a(grid["gap_start"]))
    end_gap, end_se = _a(grid["gap_end"]), _a(grid["gap_stderr_end"])
    end = np.where(np.abs(end_gap) < 3 * end_se, 0.0, np.sign(end_gap))
    cmap = ListedColormap([PALETTE["individuals"], "#dddddd", PALETTE["mean_network"]])
    axes = axes_or_new(axes, 2, 1, figsize=(WIDTH, 5.6), sharex=True)
    extent = (mu0[0], mu0[-1], sigma0[0], sigma0[-1])
    for ax, signs, title in ((axes[0], start, "before training"), (axes[1], end, "after training")):
        image = ax.imshow(
            signs.T, origin="lower", aspect="auto", extent=extent, cmap=cmap, vmin=-1.5, vmax=1.5
        )
        ax.set(title=f"sign of $\\Delta L$, {title}", ylabel=r"starting spread $\sigma_0$")
        ax.grid(False)
    axes[1].set_xlabel(r"starting mean $\mu_0$")
    bar = axes[0].figure.colorbar(image, ax=axes, ticks=[-1, 0, 1])
    bar.ax.set_yticklabels(["< 0: individuals better", "~ 0 (within 3 SE)", "> 0: mean better"])
    return axes


def breakdown(results: dict[str, Any], axes=None) -> np.ndarray:
    """Non-convex loss: measured Delta L, the second-order prediction and the exact value,
    against sigma, for several means mu."""
    data = results["breakdown"]
    sigma = _a(data["sigma"])
    axes = panels(axes, len(data["rows"]), 2.8)
    for ax, row in zip(axes, data["rows"], strict=True):
        measured, se = _a(row["measured"]), _a(row["stderr"])
        ax.errorbar(
            sigma,
            measured,
            yerr=2 * se,
            fmt="o",
            ms=3,
            color=PALETTE["sgb"],
            label="measured (Monte Carlo)",
        )
        ax.plot(sigma, _a(row["exact"]), "-", color="k", lw=1, label="exact")
        ax.plot(sigma, _a(row["predicted"]), "--", color=PALETTE["dgb"], label="second order")
        ax.axhline(0, color="grey", lw=0.8)
        ax.set(
            title=f"$\\mu$ = {row['mu']:g} ($L''$ = {row['curvature']:.2f})",
            xlabel=r"spread $\sigma$",
            ylabel=r"$\Delta L$",
        )
        ax.legend(fontsize=8)
    return axes


def network_gap(results: dict[str, Any], axes=None) -> np.ndarray:
    """Trained digits classifiers: measured Delta L (training cross-entropy; training and test
    error) against the spread scale, next to the Hessian-trace prediction; one panel above
    the other, the legends beside them."""
    networks = results["network"]
    axes = axes_or_new(axes, 2, 1, figsize=(WIDTH, 6.4))
    colors = (PALETTE["sgb"], PALETTE["dgb"], PALETTE["baseline"])
    for net, marker, color in zip(networks, "os^", colors, strict=False):
        label = "types " + types_label(net["cell_types"])
        scales = _a([s["scale"] for s in net["scales"]])

        def series(key, field="gap", scales_=net["scales"]):
            return _a([s[key][field] for s in scales_])

        ce, ce_se = series("train_cross_entropy"), series("train_cross_entropy", "stderr")
        axes[0].errorbar(
            scales, ce, yerr=2 * ce_se, fmt=marker + "-", color=color, label=f"{label}: measured"
        )
        axes[0].plot(
            scales,
            _a([s["predicted"] for s in net["scales"]]),
            marker + "--",
            color=color,
            mfc="none",
            label=f"{label}: $\\frac{{1}}{{2}}\\,\\mathrm{{tr}}(H\\,\\mathrm{{diag}}\\,\\sigma^2)$",
        )
        for key, style, fill in (
            ("train_error_rate", "-", "full"),
            ("test_error_rate", ":", "none"),
        ):
            axes[1].errorbar(
                scales,
                100 * series(key),
                yerr=200 * series(key, "stderr"),
                fmt=marker + style,
                color=color,
                mfc=color if fill == "full" else "none",
                label=f"{label}: {key.split('_')[0]} error",
            )
    axes[0].set(
        xscale="log",
        yscale="log",
        xlabel=r"spread scale $c$ ($\sigma \to c\,\sigma$)",
        ylabel=r"$\Delta L$, cross-entropy (nats)",
        title="training cross-entropy",
    )
    axes[1].axhline(0, color="grey", lw=0.8)
    axes[1].set(
        xscale="log",
        xlabel=r"spread scale $c$ ($\sigma \to c\,\sigma$)",
        ylabel=r"$\Delta$ error (percentage points)",
        title="error rate: individuals - mean network",
    )
    for ax in axes:
        ax.set_xticks(scales, [f"{c:g}" for c in scales])
        ax.minorticks_off()
        ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.02, 0.5))
    return axes


def elbo_toy(results: dict[str, Any], ax=None):
    """The ELBO's spread on the convex toy L = w^2/2: sigma over gradient steps for each KL
    weight c, trained as sigma = softplus(rho) (solid) and as sigma itself (thin), against
    the fixed point sqrt(c / (H + c lambda)) (dotted)."""
    toy = results["elbo_toy"]
    steps = _a(toy["steps"])
    kl_weights = _a(toy["kl_weights"])
    predicted = _a(toy["predicted_sigma"])
    ax = axes_or_new(ax, figsize=(WIDTH, 4.2))
    colors = ("k", PALETTE["sgb"], PALETTE["individuals"], PALETTE["dgb"], PALETTE["authors"])
    floor = 1e-3
    for i, (c, color) in enumerate(zip(kl_weights, colors, strict=False)):
        soft = _a(toy["runs"]["softplus"]["sigma"])[i]
        raw = _a(toy["runs"]["sigma"]["sigma"])[i]
        ax.plot(steps, np.maximum(soft, floor), color=color, lw=1.8, label=f"c = {c:g}")
        ax.plot(steps, np.maximum(raw, floor), color=color, lw=0.7, alpha=0.7)
        if predicted[i] > 0:
            ax.axhline(predicted[i], color=color, ls=":", lw=1.5)
    ax.plot([], [], color="grey", lw=1.8, label=r"trained as softplus($\rho$)")
    ax.plot([], [], color="grey", lw=0.7, label=r"trained as $\sigma$")
    ax.plot([], [], color="grey", ls=":", label="sqrt(c / (H + c lambda))")
    ax.set(
        yscale="log",
        ylim=(floor, 1.0),
        xlabel="gradient step",
        ylabel=r"spread $\sigma$",
        title=(
            f"L(w) = w^2/2 (H = 1), prior N(0, {toy['prior_sigma']:g}^2), "
            f"learning rate {toy['learning_rate']:g}"
        ),
    )
    ax.legend(fontsize=8, ncol=2, loc="lower left")
    return ax


def _fixed_point_points(run: Record, population: bool) -> tuple[np.ndarray, np.ndarray]:
    """Learned sigma^2 and the predicted c / (H + c lambda) over a run's type pairs, H at the
    trained means or (``population``) averaged over sampled individuals."""
    layers = run.layers.values()
    sigma2 = np.concatenate([_a(layer.sigma2) for layer in layers])
    curvature = np.concatenate(
        [_a(layer.curvature_population if population else layer.curvature) for layer in layers]
    )
    predicted = np.asarray(theory.elbo_fixed_point(curvature, run.kl_weight, run.prior_sigma))
    return sigma2, predicted


def fixed_point(fixed_points: Sequence[Record], axes=None) -> np.ndarray:
    """Each digits classifier's learned sigma^2 per type pair against c / (H + c lambda):
    top, H at the trained means; bottom, H averaged over sampled individuals; one column
    per classifier (``axes``: (2, classifiers)). One colour per training length; the
    dashed line is equality, the dotted one sigma^2 at initialisation. ``fixed_points``:
    the ``FixedPoint`` records of ``sgb.experiments.theory`` (a results file's, or
    ``compute`` output's through its ``as_record``)."""
    n = len(fixed_points)
    axes = axes_or_new(axes, 2, n, figsize=(WIDTH, 7.2), squeeze=False)
    colors = (PALETTE["baseline"], PALETTE["sgb"], PALETTE["dgb"], PALETTE["individuals"])
    for col, net in enumerate(fixed_points):
        for row, where in enumerate(("H at the trained means", "H over individuals")):
            ax = axes[row, col]
            for run, color in zip(net.runs, colors, strict=False):
                sigma2, predicted = _fixed_point_points(run, population=row == 1)
                summary = run.summary.population if row == 1 else run.summary.at_mean
                ax.scatter(
                    predicted,
                    sigma2,
                    s=6,
                    alpha=0.5,
                    color=color,
                    rasterized=True,  # thousands of points: as vectors, megabytes of SVG
                    label=(
                        f"{run.epochs} epochs: median ratio {summary.median_ratio:.2f},\n"
                        f"log corr. {summary.log_correlation:.2f}"
                    ),
                )
            first = net.runs[0]
            ax.axhline(first.sigma2_init, color="grey", ls=":", lw=1, label=r"$\sigma^2$ at init")
            lo, hi = ax.get_xlim()
            ends = np.array([min(lo, first.sigma2_init), hi])
            ax.plot(ends, ends, "k--", lw=1, label="learned = predicted")
            ax.set(
                xscale="log",
                yscale="log",
                xlabel=r"predicted $c / (H + c\lambda)$  (weight$^2$)",
                ylabel=r"learned $\sigma^2$  (weight$^2$)",
                title=f"types {types_label(net.cell_types)}, {where}",
            )
            ax.legend(fontsize=8, loc="upper left")
    return axes


def saddle(results: Record, axes=None) -> np.ndarray:
    """The Hessian at the means of chapter 3's digits classifiers (``sgb.experiments.
    saddle``'s results): left, each classifier's eigenvalues at its first seed, on a
    symmetric log axis; right, each classifier's negative-curvature share N / (N + P) of
    Theorem A.1's second-order term per seed, with their mean and 95 % interval, against
    the half above which the population would beat its mean network."""
    axes = axes_or_new(axes, 1, 2, figsize=(WIDTH, 3.4))
    colors = (PALETTE["sgb"], PALETTE["dgb"], PALETTE["baseline"])
    kinds = list(dict.fromkeys(tuple(n.cell_types) for n in results.networks))
    for i, (kind, color) in enumerate(zip(kinds, colors, strict=False)):
        mine = [n for n in results.networks if tuple(n.cell_types) == kind]
        label = "types " + types_label(kind)
        spectrum = _a(next(n.eigenvalues for n in mine if n.eigenvalues))
        edges = np.logspace(-8, 2, 41)
        up = np.histogram(spectrum[spectrum > 0], edges)[0]
        down = np.histogram(-spectrum[spectrum < 0], edges)[0]
        axes[0].stairs(up, edges, color=color, label=f"{label}: positive")
        axes[0].stairs(-down, edges, color=color, ls=":", label=f"{label}: negative (down)")
        shares = _a([n.negative_share for n in mine])
        axes[1].plot(np.full(shares.size, i), shares, "o", color=color, alpha=0.5, mfc="none")
        if shares.size > 1:
            mean, low, high = stats.mean_ci(shares)
            axes[1].errorbar(
                i + 0.2, mean, yerr=[[mean - low], [high - mean]], fmt="s", color=color
            )
    axes[0].axhline(0, color="k", lw=0.5)
    low, high = axes[0].get_ylim()
    axes[0].set_ylim(low, high + 0.7 * (high - low))  # room above the bars for the legend
    axes[0].set(
        xscale="log",
        xlabel="|eigenvalue| of H at the means (nats per weight$^2$)",
        ylabel="eigenvalues (count; negative ones down)",
        title="the Hessian's spectrum, first seed",
    )
    axes[0].legend(fontsize=8, loc="upper right")
    axes[1].axhline(0.5, color="k", ls="--", lw=1, label="N = P: the gap's sign turns")
    axes[1].set(
        xticks=range(len(kinds)),
        xticklabels=["types " + types_label(k) for k in kinds],
        xlim=(-0.5, len(kinds) - 0.5),
        ylim=(0, 1),
        ylabel="N / (N + P)",
        title="negative curvature's share, per seed",
    )
    axes[1].legend(fontsize=8, loc="upper right")
    return axes
