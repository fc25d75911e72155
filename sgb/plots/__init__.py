"""Figures of the book: one shared style here, one module of figure functions per chapter.

One convention for every figure function: the data first, then ``ax=None`` (or ``axes``
for a figure of several panels); it draws on the axes given, else on a new figure of its
own size (``axes_or_new``), and returns them.

Every figure fits the book's content column (``COLUMN_IN`` wide; a wider one is shrunk to
it, and its text with it) and its smallest text is at least ``MIN_FONT_PT`` as shown
(``shown_min_font_pt``): at most two panels a row, ``WIDTH`` wide.
"""

import math

import matplotlib.pyplot as plt
import numpy as np
import seaborn as sns
from matplotlib.figure import Figure
from matplotlib.text import Text

COLUMN_IN = 6.875  # the book's content column at 1280 px: 660 px at 96 px/in
WIDTH = 6.6  # in, every figure's width at most: with its 0.1 in margins, inside the column
MIN_FONT_PT = 8.0  # the smallest text a figure may show

PALETTE = {
    "sgb": "#1f77b4",
    "dgb": "#d62728",
    "baseline": "#555555",
    "mean_network": "#ff7f0e",
    "individuals": "#2ca02c",
    "authors": "#9467bd",
}


def apply_style() -> None:
    """The book's style, one seaborn theme: white grid, tick labels and legends at 8.5 pt,
    axis labels and titles at 9.5-10 pt, no top/right spines, matplotlib's tab10 colours (the
    PALETTE's); in a notebook, figures are shown as SVG (vector, sharp at any zoom) where the
    kernel supports it (``use_svg``)."""
    use_svg()
    sns.set_theme(
        context="paper",
        style="whitegrid",
        palette="tab10",
        rc={
            "figure.dpi": 110,
            "figure.figsize": (WIDTH, 4.0),
            "font.size": 9.5,
            "axes.titlesize": 10,
            "axes.labelsize": 9.5,
            "xtick.labelsize": 8.5,
            "ytick.labelsize": 8.5,
            "legend.fontsize": 8.5,
            "legend.title_fontsize": 9,
            "grid.alpha": 0.5,
            "axes.spines.top": False,
            "axes.spines.right": False,
            "legend.frameon": False,
        },
    )


def shown_width_in(fig: Figure) -> float:
    """``fig``'s width in inches as a notebook shows it: cut to what is drawn, plus
    0.1 in each side (the inline backend's ``bbox_inches="tight"``)."""
    fig.draw_without_rendering()  # lays the figure out
    return fig.get_tightbbox().width + 2 * 0.1


def shown_min_font_pt(fig: Figure, column_in: float = COLUMN_IN) -> float:
    """The smallest visible text of ``fig`` (tick labels, legends, titles, texts), in pt
    as shown in a column ``column_in`` inches wide: a wider figure (``shown_width_in``)
    is shrunk to it, its text with it."""
    sizes = [
        text.get_fontsize()
        for text in fig.findobj(Text)
        if text.get_visible()
        and text.get_text().strip()
        and (text.axes is None or text.axes.get_visible())
    ]
    if not sizes:
        raise ValueError("the figure has no text")
    return min(sizes) * min(1.0, column_in / shown_width_in(fig))


def panels(axes, n: int, height: float, columns: int = 2, **kwargs) -> np.ndarray:
    """``n`` panels, flat: ``axes`` if given, else a new figure ``WIDTH`` wide of at most
    ``columns`` panels a row, each row ``height`` inches tall, the spare panels hidden."""
    if axes is not None:
        return np.ravel(axes)
    cols = min(n, columns)
    rows = math.ceil(n / cols)
    grid = np.ravel(
        subplots(rows, cols, figsize=(WIDTH, height * rows), squeeze=False, **kwargs)[1]
    )
    for spare in grid[n:]:
        spare.set_visible(False)
    return grid[:n]


def use_svg() -> bool:
    """Show the notebook's inline figures as SVG; False (and nothing changed) outside an
    IPython kernel, as in the tests and scripts, where figures are saved or not shown."""
    try:
        from IPython import get_ipython
        from matplotlib_inline.backend_inline import set_matplotlib_formats
    except ImportError:
        return False
    if get_ipython() is None:
        return False
    set_matplotlib_formats("svg")
    return True


def subplots(*args, **kwargs):
    """``plt.subplots`` with the book's style and a constrained layout."""
    apply_style()
    kwargs.setdefault("layout", "constrained")
    return plt.subplots(*args, **kwargs)


def axes_or_new(ax, *args, **kwargs):
    """``ax`` (one axes or several) if given, else those of a new figure
    ``subplots(*args, **kwargs)``."""
    if ax is None:
        _, ax = subplots(*args, **kwargs)
    return ax
