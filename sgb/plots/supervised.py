"""Chapter 4 figures: innate accuracy of DGB and SGB against compression (paper Figure 2)."""

from collections.abc import Mapping, Sequence

import matplotlib.ticker as mticker
import numpy as np
from matplotlib.axes import Axes

from sgb.plots import PALETTE, WIDTH, axes_or_new, panels
from sgb.schemas import Record
from sgb.supervised_sweep import FullDgbRecord, SweepRecord, summarise_compression

_LABELS = {"sgb": "SGB (sampled individuals)", "dgb": "DGB (g-net generated)"}
_AXES = {
    "ours": "compression ratio, every parameter counted",
    "authors": "compression ratio, authors' count\n(weights / tables or g-nets)",
}
_KL = {"synapse": "KL per synapse (Bayes by backprop)", "table": "KL per type pair (genome)"}


def _band(
    ax: Axes,
    x: Sequence[float],
    mean: Sequence[float],
    sem: Sequence[float | None],
    color: str,
    label: str,
    **style,
) -> None:
    """Mean accuracy (a fraction) +- its SEM (NaN or None: no bar) against compression."""
    x, mean = np.asarray(x), np.asarray(mean)
    err = np.nan_to_num(np.asarray(sem, dtype=float))
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


def _curve(ax: Axes, curve: Record, color: str, label: str, **style) -> None:
    """A summary's curve (``sgb.experiments.fig2.Curve``) as a band."""
    _band(ax, curve.compression, curve.mean, curve.sem, color, label, **style)


def _summarised(records: Sequence[SweepRecord], model: str) -> dict[str, list]:
    """``summarise_compression`` of ``records`` (our count) for ``model``: setting,
    compression, mean, SEM and seeds."""
    return summarise_compression([r.model_dump() for r in records])[model]


def _table(ax: Axes, table: Mapping[str, list], color: str, label: str, **style) -> None:
    """A ``summarise_compression`` table as a band."""
    _band(ax, table["compression"], table["mean"], table["sem"], color, label, **style)


def plot_accuracy_vs_compression(
    results: Record,
    convention: str = "ours",
    mean_network: bool = True,
    ax: Axes | None = None,
) -> Axes:
    """One panel of a Figure 2 sweep (``results``: its ``Fig2Results``): SGB and DGB mean
    innate test accuracy (%) +- SEM over seeds against compression under ``convention``
    (log axis), each seed a faint dot, the SGB's mean network, the uncompressed network
    (dotted) and the SGB/DGB crossovers (thin vertical lines)."""
    ax = axes_or_new(ax, figsize=(5.2, 4.0))
    part = results.ours if convention == "ours" else results.authors
    summary = part.summary
    for kind, curve in (("dgb", summary.dgb), ("sgb", summary.sgb)):
        _curve(ax, curve, PALETTE[kind], _LABELS[kind])
        seeds = [r for r in results.records if r.model == kind]
        ax.scatter(
            [r.compression if convention == "ours" else r.compression_authors for r in seeds],
            [100 * r.accuracy for r in seeds],
            s=6,
            alpha=0.35,
            color=PALETTE[kind],
            linewidths=0,
        )
    if mean_network:
        table = part.summary_mean_network.sgb
        _curve(ax, table, PALETTE["mean_network"], "SGB mean network", ls="--")
    base = 100 * np.mean(summary.dense.mean)
    ax.axhline(base, color=PALETTE["baseline"], ls=":", label="uncompressed network")
    for point in part.crossovers:
        ax.axvline(point, color="k", lw=0.8, alpha=0.5)
    _log_x(ax)
    ax.set_xlabel(_AXES[convention])
    ax.set_ylabel("innate test accuracy (%)")
    ax.set_title(str(results.dataset))
    return ax


def figure2(results_by_dataset: Mapping[str, Record], axes=None) -> np.ndarray:
    """Figure 2, every parameter counted: one panel per dataset (its sweep's
    ``Fig2Results``; ``axes``: as many), two a row."""
    n = len(results_by_dataset)
    axes = panels(axes, n, 3.4)
    for ax, results in zip(axes, results_by_dataset.values(), strict=True):
        plot_accuracy_vs_compression(results, ax=ax)
    axes[0].legend(fontsize=8, loc="lower left")
    return axes


def figure2_conventions(results: Record, axes=None) -> np.ndarray:
    """Figure 2 for one dataset (its ``Fig2Results``) under both counting conventions, side
    by side (2 axes)."""
    axes = axes_or_new(axes, 1, 2, figsize=(WIDTH, 3.8), sharey=True)
    for ax, convention in zip(axes, ("ours", "authors"), strict=True):
        plot_accuracy_vs_compression(results, convention, ax=ax)
    axes[0].legend(fontsize=8, loc="lower left")
    return axes


def plot_kl_counting(results: Record, main_counting: str, ax: Axes | None = None) -> Axes:
    """SGB innate accuracy with the sweep's KL counting ``main_counting`` and the other one
    (the ablation), at the ablation's compression ratios, mean +- SEM over seeds
    (``results``: the sweep's ``Fig2Results``)."""
    ax = axes_or_new(ax, figsize=(5.2, 3.8))
    other = "table" if main_counting == "synapse" else "synapse"
    table = _summarised([r for r in results.records if r.model == "sgb"], "sgb")
    ablation = _summarised(results.ablation_records, "sgb")
    _table(ax, table, PALETTE["sgb"], _KL[main_counting])
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
    ax.set_title(f"{results.dataset}: how the KL is counted")
    ax.legend(fontsize=8)
    return ax


def plot_dgb_budget(budget: Record, dense: Record, ax: Axes | None = None) -> Axes:
    """The DGB budget run (``budget``: its ``DgbBudgetResults``): innate test accuracy (%)
    of the best-validation network and of the network generated at each record, against
    write-back rounds; the uncompressed network's mean +- SEM over seeds (``dense``: a
    sweep summary's ``Curve``) and 3 points below it."""
    ax = axes_or_new(ax, figsize=(6.4, 4.0))
    records = budget.records
    rounds = [r.rounds for r in records]
    ax.plot(
        rounds,
        [100 * r.test_accuracy for r in records],
        color=PALETTE["dgb"],
        marker="o",
        ms=4,
        label="DGB, best on validation (innate network)",
    )
    ax.plot(
        rounds,
        [100 * r.generated_test_accuracy for r in records],
        color=PALETTE["dgb"],
        alpha=0.5,
        ls="--",
        label="DGB, generated at that round",
    )
    sem = dense.sem[0]
    base, err = 100 * dense.mean[0], 0.0 if sem is None else 100 * sem
    ax.axhspan(base - err, base + err, color=PALETTE["baseline"], alpha=0.3, lw=0)
    ax.axhline(base, color=PALETTE["baseline"], ls=":", label="uncompressed network")
    ax.axhline(base - 3, color=PALETTE["baseline"], lw=0.8, label="3 points below it")
    ax.set_xlabel("write-back rounds (100 p-net minibatches, 600 g-net steps each)")
    ax.set_ylabel("innate test accuracy (%)")
    ax.set_title(
        f"{budget.dataset}: DGB at {budget.compression_ours:.0f}x "
        f"(g-net width {records[-1].gnet_width})"
    )
    ax.legend(fontsize=8, loc="lower right")
    return ax


_VARIANT_STYLE = {
    "authors": (PALETTE["sgb"], "-", "SGB as the authors train it (KL per synapse, rho -7)"),
    "per_pair": (PALETTE["individuals"], "--", "SGB, KL per type pair (rho -7)"),
    "rho_ours": (PALETTE["authors"], ":", "SGB, KL per synapse, rho -5"),
}


def plot_full_budgets(
    sgb_full: Record,
    dgb_records: list[FullDgbRecord],
    sweep: Record,
    ax: Axes | None = None,
) -> Axes:
    """Figure 2 at the authors' budgets: each SGB variant of ``sgb_full`` (the results of
    ``sgb.experiments.sgb_full``) and the finished full-budget DGB cells (``dgb_records``,
    ``sgb.supervised_sweep.figure2_records``), mean innate test accuracy (%) +- SEM over
    seeds against compression (ours); the cpu sweep's DGB and uncompressed network
    (``sweep``: Figure 2's results) for reference."""
    ax = axes_or_new(ax, figsize=(6.4, 4.4))
    cells = list(sgb_full.cells.values())
    for variant, (color, style, label) in _VARIANT_STYLE.items():
        records = [c for c in cells if c.variant == variant]
        if records:
            _table(ax, _summarised(records, "sgb"), color, label, ls=style)
    if dgb_records:
        _table(ax, _summarised(dgb_records, "dgb"), PALETTE["dgb"], "DGB, authors' layout")
    summary = sweep.ours.summary
    _curve(ax, summary.dgb, PALETTE["dgb"], "DGB, the cpu sweep", ls=":", alpha=0.4)
    base = 100 * np.mean(summary.dense.mean)
    ax.axhline(base, color=PALETTE["baseline"], ls=":", label="uncompressed network")
    _log_x(ax)
    ax.set_xlabel(_AXES["ours"])
    ax.set_ylabel("innate test accuracy (%)")
    ax.set_title(f"{sgb_full.dataset}: SGB 50 epochs, DGB 500 rounds")
    ax.legend(fontsize=8, loc="lower left")
    return ax
