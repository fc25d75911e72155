"""Chapter 4 figure: individuals, mean network and moment-matched network of each SGB cell
(``sgb.experiments.mean_gap``)."""

import numpy as np
from matplotlib.axes import Axes

from sgb.plots import PALETTE, axes_or_new
from sgb.schemas import Record

_SERIES = (
    ("accuracy", "individuals (sampled)", PALETTE["individuals"]),
    ("mean_network", "mean network", PALETTE["mean_network"]),
    ("moment_network", "moment-matched network", PALETTE["sgb"]),
)


def _cell_label(row: Record) -> str:
    return f"{row.compression:.0f}x\n$\\rho$ = {row.rho_init:g}"


def plot_mean_gap(results: Record, ax: Axes | None = None) -> Axes:
    """Grouped bars: per cell (compression, rho start) of ``results.summary`` (``results``:
    ``sgb.experiments.mean_gap``'s ``MeanGapResults``), the test
    accuracy (%) of the individuals, the mean network and the moment-matched network, mean
    over seeds with SEM error bars (none with one seed). Returns ``ax``."""
    ax = axes_or_new(ax, figsize=(6.4, 3.8))
    rows = results.summary
    x = np.arange(len(rows))
    width = 0.8 / len(_SERIES)
    for i, (key, label, color) in enumerate(_SERIES):
        mean = 100 * np.array([getattr(row, key) for row in rows], dtype=float)
        sems = [getattr(row, f"{key}_sem") for row in rows]
        err = 100 * np.nan_to_num(np.array(sems, dtype=float))
        ax.bar(
            x + (i - (len(_SERIES) - 1) / 2) * width,
            mean,
            width,
            yerr=err,
            capsize=2,
            color=color,
            label=label,
        )
    ax.set_xticks(x, [_cell_label(row) for row in rows])
    ax.set_ylabel("innate test accuracy (%)")
    ax.set_xlabel(r"compression (every parameter counted), $\rho$ at the start")
    ax.set_title(str(results.dataset))
    ax.set_ylim(0, 100)
    ax.legend(fontsize=8, loc="upper right")
    return ax
