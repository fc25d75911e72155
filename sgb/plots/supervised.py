"""Chapter 4 figures: innate accuracy of DGB and SGB against compression (paper Figure 2)."""

from collections.abc import Mapping
from typing import Any

import matplotlib.ticker as mticker
import numpy as np
from matplotlib.axes import Axes

from sgb.plots import PALETTE, WIDTH, axes_or_new, panels
from sgb.supervised_sweep import summarise_compression

_LABELS = {"sgb": "SGB (sampled individuals)", "dgb": "DGB (g-net generated)"}
_AXES = {
    "ours": "compression ratio, every parameter counted",
    "authors": "compression ratio, authors' count\n(weights / tables or g-nets)",
}
_KL = {"synapse": "KL per synapse (Bayes by backprop)", "table": "KL per type pair (genome)"}


def _band(ax: Axes, table: Mapping[str, list], color: str, label: str, **style) -> None:
    x, mean = np.asarray(table["compression"]), np.asarray(table["mean"])
    err = np.nan_to_num(np.asarray(table["sem"], dtype=float))
    ax.errorbar(
        x,
        100 * mean,
        yerr=100 * err,
        color=color,
        label=label,
        marker="o",
        ms=4,
        capsize=2,
        **style,
    )


def _log_x(ax: Axes) -> None:
    ax.set_xscale("log")
    plain = mticker.FuncFormatter(lambda value, _: f"{value:g}")
    ax.xaxis.set_major_formatter(plain)
    ax.xaxis.set_minor_formatter(mticker.NullFormatter())


def plot_accuracy_vs_compression(
    results: Mapping[str, Any],
    convention: str = "ours",
    mean_network: bool = True,
    ax: Axes | None = None,
) -> Axes:
    """One panel: SGB and DGB mean innate test accuracy (%) +- SEM over seeds against
    compression under ``convention`` (log axis), each seed a faint dot (from ``records``
    where the results hold them), the SGB's mean network, the uncompressed network (dotted)
    and the SGB/DGB crossovers (thin vertical lines)."""
    ax = axes_or_new(ax, figsize=(5.2, 4.0))
    part = results[convention]
    summary = part["summary"]
    x_of = "compression" if convention == "ours" else "compression_authors"
    for kind in ("dgb", "sgb"):
        if kind in summary:
            _band(ax, summary[kind], PALETTE[kind], _LABELS[kind])
            seeds = [r for r in results.get("records", ()) if r["model"] == kind]
            ax.scatter(
                [r[x_of] for r in seeds],
                [100 * r["accuracy"] for r in seeds],
                s=6,
                alpha=0.35,
                color=PALETTE[kind],
                linewidths=0,
            )
    if mean_network and part.get("summary_mean_network", {}).get("sgb"):
        table = part["summary_mean_network"]["sgb"]
        _band(ax, table, PALETTE["mean_network"], "SGB mean network", ls="--")
    if "dense" in summary:
        base = 100 * np.mean(summary["dense"]["mean"])
        ax.axhline(base, color=PALETTE["baseline"], ls=":", label="uncompressed network")
    for point in part.get("crossovers", []):
        ax.axvline(point, color="k", lw=0.8, alpha=0.5)
    _log_x(ax)
    ax.set_xlabel(_AXES[convention])
    ax.set_ylabel("innate test accuracy (%)")
    ax.set_title(str(results["dataset"]))
    return ax


def figure2(results_by_dataset: Mapping[str, Mapping[str, Any]], axes=None) -> np.ndarray:
    """Figure 2, every parameter counted: one panel per dataset (``axes``: as many), two
    a row."""
    n = len(results_by_dataset)
    axes = panels(axes, n, 3.4)
    for ax, results in zip(axes, results_by_dataset.values(), strict=True):
        plot_accuracy_vs_compression(results, ax=ax)
    axes[0].legend(fontsize=8, loc="lower left")
    return axes


def figure2_conventions(results: Mapping[str, Any], axes=None) -> np.ndarray:
    """Figure 2 for one dataset under both counting conventions, side by side (2 axes)."""
    axes = axes_or_new(axes, 1, 2, figsize=(WIDTH, 3.8), sharey=True)
    for ax, convention in zip(axes, ("ours", "authors"), strict=True):
        plot_accuracy_vs_compression(results, convention, ax=ax)
    axes[0].legend(fontsize=8, loc="lower left")
    return axes


def plot_kl_counting(
    results: Mapping[str, Any], main_counting: str, ax: Axes | None = None
) -> Axes:
    """SGB innate accuracy with the sweep's KL counting ``main_counting`` and the other one
    (the ablation), at the ablation's compression ratios, mean +- SEM over seeds."""
    ax = axes_or_new(ax, figsize=(5.2, 3.8))
    other = "table" if main_counting == "synapse" else "synapse"
    table = summarise_compression([r for r in results["records"] if r["model"] == "sgb"])["sgb"]
    ablation = summarise_compression(results["ablation_records"])["sgb"]
    _band(ax, table, PALETTE["sgb"], _KL[main_counting])
    ax.errorbar(
        ablation["compression"],
        100 * np.asarray(ablation["mean"]),
        yerr=100 * np.nan_to_num(np.asarray(ablation["sem"], dtype=float)),
        color=PALETTE["individuals"],
        marker="s",
        ls="none",
        capsize=3,
        label=_KL[other],
    )
    _log_x(ax)
    ax.set_xlabel(_AXES["ours"])
    ax.set_ylabel("innate test accuracy (%)")
    ax.set_title(f"{results['dataset']}: how the KL is counted")
    ax.legend(fontsize=8)
    return ax


def plot_dgb_budget(
    budget: Mapping[str, Any], dense: Mapping[str, list], ax: Axes | None = None
) -> Axes:
    """The DGB budget run (``sgb.experiments.dgb_budget``): innate test accuracy (%) of the
    best-validation network and of the network generated at each record, against write-back
    rounds; the uncompressed network's mean +- SEM over seeds (``dense``: a sweep summary
    row) and 3 points below it."""
    ax = axes_or_new(ax, figsize=(6.4, 4.0))
    records = budget["records"]
    rounds = [r["rounds"] for r in records]
    ax.plot(
        rounds,
        [100 * r["test_accuracy"] for r in records],
        color=PALETTE["dgb"],
        marker="o",
        ms=4,
        label="DGB, best on validation (innate network)",
    )
    ax.plot(
        rounds,
        [100 * r["generated_test_accuracy"] for r in records],
        color=PALETTE["dgb"],
        alpha=0.5,
        ls="--",
        label="DGB, generated at that round",
    )
    base, err = 100 * dense["mean"][0], 100 * np.nan_to_num(dense["sem"][0])
    ax.axhspan(base - err, base + err, color=PALETTE["baseline"], alpha=0.3, lw=0)
    ax.axhline(base, color=PALETTE["baseline"], ls=":", label="uncompressed network")
    ax.axhline(base - 3, color=PALETTE["baseline"], lw=0.8, label="3 points below it")
    ax.set_xlabel("write-back rounds (100 p-net minibatches, 600 g-net steps each)")
    ax.set_ylabel("innate test accuracy (%)")
    ax.set_title(
        f"{budget['dataset']}: DGB at {budget['compression_ours']:.0f}x "
        f"(g-net width {records[-1]['gnet_width']})"
    )
    ax.legend(fontsize=8, loc="lower right")
    return ax


_VARIANT_STYLE = {
    "authors": (PALETTE["sgb"], "-", "SGB as the authors train it (KL per synapse, rho -7)"),
    "per_pair": (PALETTE["individuals"], "--", "SGB, KL per type pair (rho -7)"),
    "rho_ours": (PALETTE["authors"], ":", "SGB, KL per synapse, rho -5"),
}


def plot_full_budgets(
    sgb_full: Mapping[str, Any],
    dgb_records: list[dict],
    sweep: Mapping[str, Any],
    ax: Axes | None = None,
) -> Axes:
    """Figure 2 at the authors' budgets: each SGB variant of ``sgb_full`` (the results of
    ``sgb.experiments.sgb_full``) and the finished full-budget DGB cells (``dgb_records``,
    ``sgb.supervised_sweep.figure2_records``), mean innate test accuracy (%) +- SEM over
    seeds against compression (ours); the cpu sweep's DGB and uncompressed network
    (``sweep``: Figure 2's results) for reference."""
    ax = axes_or_new(ax, figsize=(6.4, 4.4))
    cells = list(sgb_full["cells"].values())
    for variant, (color, style, label) in _VARIANT_STYLE.items():
        records = [c for c in cells if c["variant"] == variant]
        if records:
            _band(ax, summarise_compression(records)["sgb"], color, label, ls=style)
    if dgb_records:
        _band(ax, summarise_compression(dgb_records)["dgb"], PALETTE["dgb"], "DGB, authors' layout")
    summary = sweep["ours"]["summary"]
    _band(ax, summary["dgb"], PALETTE["dgb"], "DGB, the cpu sweep", ls=":", alpha=0.4)
    base = 100 * np.mean(summary["dense"]["mean"])
    ax.axhline(base, color=PALETTE["baseline"], ls=":", label="uncompressed network")
    _log_x(ax)
    ax.set_xlabel(_AXES["ours"])
    ax.set_ylabel("innate test accuracy (%)")
    ax.set_title(f"{sgb_full['dataset']}: SGB 50 epochs, DGB 500 rounds")
    ax.legend(fontsize=8, loc="lower left")
    return ax
