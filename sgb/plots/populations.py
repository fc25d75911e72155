"""Figures of the ``populations`` experiment (``sgb.experiments.populations``): how well
the episodes tell a genome's individuals apart, and Figure 5's difference per genome and
pooled."""

import numpy as np

from sgb.plots import PALETTE, axes_or_new
from sgb.schemas import Record

BODY_STYLE = {"normal": ("sgb", "o", "normal legs"), "long_legs": ("dgb", "s", "long legs")}
SETTINGS_COLOR = {"ours": "sgb", "authors": "authors"}


def _finished(genomes: dict[str, Record]) -> dict[str, Record]:
    """The genome records (label -> record) that have their summary."""
    return {label: g for label, g in genomes.items() if g.summary is not None}


def plot_icc(genomes: dict[str, Record], ax=None):
    """Per genome (one row each), the one-episode ICC of each body with its 95 % F
    interval; ``genomes``: the results' genomes (label ->
    ``sgb.experiments.populations.PopulationGenome``)."""
    ax = axes_or_new(ax)
    done = _finished(genomes)
    rows = np.arange(len(done))
    offsets = (-0.12, 0.12)
    for offset, (body, (color, marker, label)) in zip(offsets, BODY_STYLE.items(), strict=True):
        splits = [getattr(g.summary, body).variance_split for g in done.values()]
        icc = np.array([s.icc for s in splits])
        low, high = (np.array([s.icc_ci[i] for s in splits]) for i in (0, 1))
        ax.errorbar(
            icc,
            rows + offset,
            xerr=[icc - low, high - icc],
            fmt=marker,
            capsize=3,
            color=PALETTE[color],
            label=label,
        )
    ax.axvline(0.0, color=PALETTE["baseline"], ls="--", lw=1)
    ax.set_yticks(rows, list(done))
    ax.invert_yaxis()
    episodes = next(iter(done.values())).summary.normal.variance_split.episodes
    ax.set_xlabel(f"ICC of one episode (95 % interval; {episodes} episodes each)")
    ax.legend(loc="best", fontsize=8)
    return ax


def plot_differences(results: Record, ax=None):
    """Figure 5 per genome: the individuals' return minus the mean network's, in percent
    of the mean network's, with its paired 95 % interval; below, each setting's pooled
    value (fixed effect, filled) and the interval over its genomes (Student t, open);
    ``results``: ``sgb.experiments.populations.PopulationsResults``."""
    ax = axes_or_new(ax)
    done = _finished(results.genomes)
    labels = list(done)
    for row, g in enumerate(done.values()):
        d = g.summary.mean_network
        color = PALETTE[SETTINGS_COLOR[g.settings]]
        _interval(ax, row, d.percent, d.percent_ci, color, "o", True)
    for settings, pooled in results.pooled.items():
        color = PALETTE[SETTINGS_COLOR[settings]]
        percent = pooled.mean_network_percent
        fixed, spread = percent.fixed_effect, percent.between_genomes
        _interval(ax, len(labels), fixed.estimate, fixed.ci, color, "D", True)
        labels.append(f"{settings}, pooled ({pooled.n_genomes} genomes)")
        _interval(ax, len(labels), spread.mean, spread.ci, color, "D", False)
        labels.append(f"{settings}, over genomes")
    ax.axvline(0.0, color=PALETTE["mean_network"], ls="--", lw=1, label="mean network")
    ax.set_yticks(range(len(labels)), labels)
    ax.invert_yaxis()
    ax.set_xlabel("individuals - mean network, % of its return (95 % intervals)")
    ax.legend(loc="best", fontsize=8)
    return ax


def _interval(ax, row: int, value: float, ci, color: str, marker: str, filled: bool) -> None:
    low, high = (np.nan if v is None else v for v in ci)
    ax.errorbar(
        [value],
        [row],
        xerr=[[value - low], [high - value]],
        fmt=marker,
        capsize=3,
        color=color,
        mfc=color if filled else "none",
    )
