"""Figures of chapter 1's model: a type table expanded to a weight matrix, individuals
sampled from one genome, and a drawing of the whole model (the paper's Figure 1).

Weight matrices are drawn with presynaptic neurons down the rows and postsynaptic
neurons along the columns, the layout of ``W[a, b]``, in one diverging colour map
symmetric about zero; every function draws on the axes given (``ax``/``axes``; new ones
if none) and returns them.
"""

from collections.abc import Sequence

import matplotlib as mpl
import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.patches import FancyArrowPatch, Rectangle

from sgb.celltypes import assign_cell_types, expand_table, type_sizes
from sgb.plots import WIDTH, axes_or_new, panels

WEIGHTS = mpl.colormaps["RdBu_r"]  # negative blue, positive red
SPREADS = mpl.colormaps["Purples"]
PRE_COLORS = ("#e6ab02", "#1b9e77", "#7570b3", "#66a61e")  # presynaptic types, circles
POST_COLORS = ("#e7298a", "#a6761d", "#666666", "#17becf")  # postsynaptic types, squares


def _limit(*arrays, limit: float | None = None) -> float:
    """The colour scale's half-width: ``limit``, else the largest |weight| of ``arrays``."""
    if limit is not None:
        return float(limit)
    return float(max(np.max(np.abs(np.asarray(a))) for a in arrays)) or 1.0


def _weights_norm(limit: float) -> mpl.colors.Normalize:
    return mpl.colors.Normalize(vmin=-limit, vmax=limit)


def type_boundaries(n: int, k: int) -> np.ndarray:
    """Where ``k`` balanced cell types of ``n`` neurons meet, in image coordinates (the
    k - 1 half-integer positions between the last neuron of one type and the next)."""
    return np.cumsum(type_sizes(n, k))[:-1] - 0.5


def weight_matrix(
    matrix,
    types: Sequence[int] | None = None,
    limit: float | None = None,
    title: str | None = None,
    labels: bool = True,
    ax: Axes | None = None,
) -> Axes:
    """``matrix`` (n_in, n_out) as an image in the weight colours, symmetric about 0 up to
    ``limit`` (default its largest |weight|); ``types`` = (k_in, k_out) draws the borders
    of the type-pair blocks."""
    ax = axes_or_new(ax)
    matrix = np.asarray(matrix)
    if matrix.ndim != 2:
        raise ValueError(f"matrix must be 2-D (n_in, n_out), got shape {matrix.shape}")
    limit = _limit(matrix, limit=limit)
    ax.imshow(matrix, cmap=WEIGHTS, norm=_weights_norm(limit), interpolation="nearest")
    if types is not None:
        k_in, k_out = types
        for y in type_boundaries(matrix.shape[0], k_in):
            ax.axhline(y, color="black", lw=1.2)
        for x in type_boundaries(matrix.shape[1], k_out):
            ax.axvline(x, color="black", lw=1.2)
    ax.grid(False)
    ax.set_xticks([])
    ax.set_yticks([])
    if max(matrix.shape) <= 40:  # thin white lines between the neurons of small matrices
        ax.set_xticks(np.arange(matrix.shape[1] + 1) - 0.5, minor=True)
        ax.set_yticks(np.arange(matrix.shape[0] + 1) - 0.5, minor=True)
        ax.grid(which="minor", color="white", lw=0.6, alpha=0.8)
        ax.tick_params(which="minor", length=0)
    if labels:
        ax.set_xlabel("postsynaptic neuron $b$")
        ax.set_ylabel("presynaptic neuron $a$")
    if title is not None:
        ax.set_title(title, fontsize=9.5)
    return ax


def expansion(table, shape: Sequence[int], axes: Sequence[Axes] | None = None) -> Sequence[Axes]:
    """A type table (k_in, k_out), each entry written in its cell (left), and the full
    weight matrix ``expand_table(table, shape)`` it expands to (right), in one colour
    scale, the blocks of each type pair outlined."""
    axes = axes_or_new(axes, 1, 2, figsize=(WIDTH, 3.4), width_ratios=[2, 3])
    table = np.asarray(table)
    full = np.asarray(expand_table(table, tuple(shape)))
    limit = _limit(table)
    left, right = axes
    weight_matrix(
        table, limit=limit, title=f"type table, {table.shape[0]} x {table.shape[1]}", ax=left
    )
    left.set_xlabel("postsynaptic type $j$")
    left.set_ylabel("presynaptic type $i$")
    for (i, j), value in np.ndenumerate(table):
        dark = abs(value) > 0.6 * limit
        color = "white" if dark else "black"
        left.text(j, i, f"{value:.2g}", ha="center", va="center", fontsize=9, color=color)
    weight_matrix(
        full,
        types=table.shape,
        limit=limit,
        title=f"expanded weight matrix, {full.shape[0]} x {full.shape[1]}",
        ax=right,
    )
    return axes


def individuals(
    kernels,
    types: Sequence[int],
    limit: float | None = None,
    axes: Sequence[Axes] | None = None,
) -> Sequence[Axes]:
    """The weight matrices of individuals side by side, ``kernels`` (N, n_in, n_out), one
    per axes, in one colour scale, the type-pair blocks outlined; only the first panel
    names its axes."""
    kernels = np.asarray(kernels)
    n = len(kernels)
    axes = panels(axes, n, 2.6, columns=4)
    if len(axes) != n:
        raise ValueError(f"{len(kernels)} individuals need as many axes, got {len(axes)}")
    limit = _limit(kernels, limit=limit)
    for q, (ax, kernel) in enumerate(zip(axes, kernels, strict=True)):
        weight_matrix(kernel, types, limit, f"individual {q + 1}", labels=q == 0, ax=ax)
    return axes


def pair_moments(kernels, types: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    """The mean and standard deviation of the weights of each type pair, each (k_in,
    k_out), over every synapse of the pair's block in every individual of ``kernels``
    (N, n_in, n_out): what development makes of the genome's mu and sigma."""
    kernels = np.asarray(kernels, dtype=np.float64)
    if kernels.ndim == 2:
        kernels = kernels[None]
    k_in, k_out = types
    rows = assign_cell_types(kernels.shape[1], k_in)
    cols = assign_cell_types(kernels.shape[2], k_out)
    mean, sd = np.zeros((k_in, k_out)), np.zeros((k_in, k_out))
    for i in range(k_in):
        for j in range(k_out):
            block = kernels[:, rows == i][:, :, cols == j]
            mean[i, j], sd[i, j] = block.mean(), block.std(ddof=1)
    return mean, sd


def _type_color(t: int, marker: str) -> str:
    """Type ``t``'s colour: presynaptic types ("o") from ``PRE_COLORS``, postsynaptic ones
    ("s") from ``POST_COLORS``."""
    colors = PRE_COLORS if marker == "o" else POST_COLORS
    return colors[t % len(colors)]


def _table(ax, values, x0, y0, cell, colors, label):
    """Draw a type table as coloured squares, row i from the top; returns its patches."""
    k_in, k_out = values.shape
    patches = []
    for (i, j), value in np.ndenumerate(values):
        patch = Rectangle(
            (x0 + j * cell, y0 + (k_in - 1 - i) * cell),
            cell,
            cell,
            facecolor=colors(value),
            edgecolor="black",
            lw=0.8,
        )
        ax.add_patch(patch)
        patches.append(patch)
    top = y0 + k_in * cell
    ax.text(x0 + k_out * cell / 2, top + 0.12, label, ha="center", va="bottom", fontsize=9)
    for i in range(k_in):  # the presynaptic type of each row
        y = y0 + (k_in - 1 - i + 0.5) * cell
        ax.plot(x0 - 0.16, y, "o", ms=5, color=_type_color(i, "o"), mec="black")
    for j in range(k_out):  # the postsynaptic type of each column
        x = x0 + (j + 0.5) * cell
        ax.plot(x, y0 - 0.16, "s", ms=5, color=_type_color(j, "s"), mec="black")
    return patches


def model_schematic(mu, sigma, kernels, limit: float | None = None, ax: Axes | None = None) -> Axes:
    """The model in one picture, as the paper's Figure 1 draws it: the genome's type
    tables of means ``mu`` and spreads ``sigma`` (k_in, k_out), development drawing every
    synapse from its pair's normal distribution, and the individuals that result,
    ``kernels`` (N, n_in, n_out), each a network whose neurons are coloured by type
    (circles presynaptic, squares postsynaptic) and whose synapses are coloured by weight,
    thicker the larger |weight|.

    The table squares are ``ax.patches`` (mu's first, then sigma's, row by row) and each
    individual's synapses one ``LineCollection`` of ``ax.collections`` (row-major over
    (a, b)), so what is drawn can be read back.
    """
    ax = axes_or_new(ax, figsize=(WIDTH, 2.6))
    mu, sigma, kernels = np.asarray(mu), np.asarray(sigma), np.asarray(kernels)
    if mu.shape != sigma.shape or mu.ndim != 2:
        raise ValueError(f"mu and sigma must be equal 2-D tables, got {mu.shape}, {sigma.shape}")
    if kernels.ndim != 3:
        raise ValueError(f"kernels must be (N, n_in, n_out), got shape {kernels.shape}")
    k_in, k_out = mu.shape
    n_ind, n_in, n_out = kernels.shape
    limit = _limit(mu, kernels, limit=limit)
    weights = _weights_norm(limit)
    spread_top = float(np.max(sigma)) or 1.0

    cell = 0.42
    _table(ax, mu, 0.4, 2.15, cell, lambda v: WEIGHTS(weights(v)), "means $\\mu_{ij}$")
    _table(
        ax,
        sigma,
        0.4,
        0.25,
        cell,
        lambda v: SPREADS(0.15 + 0.85 * v / spread_top),
        "spreads $\\sigma_{ij}$",
    )
    ax.text(0.4 + k_out * cell / 2, 4.05, "genome", ha="center", fontsize=10, weight="bold")

    start = 0.4 + k_out * cell + 0.35
    ax.add_patch(
        FancyArrowPatch(
            (start, 2.0),
            (start + 1.9, 2.0),
            arrowstyle="-|>",
            mutation_scale=16,
            lw=1.5,
            color="black",
        )
    )
    ax.text(start + 0.95, 2.2, "development", ha="center", va="bottom", fontsize=9)
    rule = "$W_{ab} \\sim \\mathcal{N}(\\mu_{ij},\\,\\sigma_{ij}^2)$"
    ax.text(start + 0.95, 1.8, rule, ha="center", va="top", fontsize=9)

    in_types, out_types = assign_cell_types(n_in, k_in), assign_cell_types(n_out, k_out)
    width, gap = 2.2, 0.45
    x_first = start + 2.4
    for q, kernel in enumerate(kernels):
        x0 = x_first + q * (width + gap)
        x_in = x0 + np.linspace(0, width, n_in)
        margin = width * (1 - n_out / max(n_in, n_out)) / 2
        x_out = x0 + np.linspace(margin, width - margin, n_out)
        y_in, y_out = 0.6, 3.2
        segments = [[(x_in[a], y_in), (x_out[b], y_out)] for a in range(n_in) for b in range(n_out)]
        flat = kernel.ravel()
        ax.add_collection(
            LineCollection(
                segments,
                colors=WEIGHTS(weights(flat)),
                linewidths=0.3 + 2.7 * np.abs(flat) / limit,
                zorder=1,
            )
        )
        for x, y, kinds, marker in ((x_in, y_in, in_types, "o"), (x_out, y_out, out_types, "s")):
            colors = [_type_color(t, marker) for t in kinds]
            ax.scatter(
                x, np.full(x.size, y), s=40, c=colors, marker=marker, edgecolors="black", zorder=2
            )
        ax.text(x0 + width / 2, 0.1, f"individual {q + 1}", ha="center", va="center", fontsize=9)
    right = x_first + n_ind * (width + gap) - gap
    ax.text((x_first + right) / 2, 4.05, "individuals", ha="center", fontsize=10, weight="bold")
    ax.set_xlim(0, right + 0.2)
    ax.set_ylim(-0.15, 4.3)
    ax.set_aspect("equal")
    ax.axis("off")
    return ax
