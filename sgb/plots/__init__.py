"""Figures of the book: one shared style here, one module of figure functions per chapter.

One convention for every figure function: the data first, then ``ax=None`` (or ``axes``
for a figure of several panels); it draws on the axes given, else on a new figure of its
own size (``axes_or_new``), and returns them.
"""

import matplotlib as mpl
import matplotlib.pyplot as plt

PALETTE = {
    "sgb": "#1f77b4",
    "dgb": "#d62728",
    "baseline": "#555555",
    "mean_network": "#ff7f0e",
    "individuals": "#2ca02c",
    "authors": "#9467bd",
}


def apply_style() -> None:
    """The book's matplotlib style: readable sizes, light grid, no top/right spines; in a
    notebook, figures are shown as SVG (vector, sharp at any zoom) where the kernel
    supports it (``use_svg``)."""
    use_svg()
    mpl.rcParams.update(
        {
            "figure.dpi": 110,
            "figure.figsize": (6.0, 4.0),
            "axes.grid": True,
            "grid.alpha": 0.3,
            "axes.spines.top": False,
            "axes.spines.right": False,
            "axes.titlesize": 11,
            "axes.labelsize": 10,
            "legend.frameon": False,
        }
    )


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
