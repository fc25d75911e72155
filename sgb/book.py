"""What the chapters share: values glued into their prose.

``glue(name, text)`` stores ``text`` (markdown) under ``name`` for the chapters'
``{glue:md}`name``` roles, so that no number or verdict in the prose is typed by hand.
Where the book's builder (myst-nb) is not installed, as on Colab, it does nothing: only
the built book reads glued values.
"""

from sgb.claims import Row


def glue(name: str, text: str) -> None:
    """Store ``text`` as markdown under ``name`` for ``{glue:md}`` roles (not shown here)."""
    try:
        from IPython.display import Markdown
        from myst_nb import glue as myst_glue
    except ImportError:
        return
    myst_glue(name, Markdown(text), display=False)


def glue_row(name: str, row: Row) -> None:
    """Glue a scorecard row's verdict, estimate with interval, detectable effect and the
    budget that would decide, as ``{name}_verdict``, ``{name}_ours``,
    ``{name}_detectable`` and ``{name}_decide``."""
    glue(f"{name}_verdict", f"**{row.verdict}**")
    glue(f"{name}_ours", row.ours)
    glue(f"{name}_detectable", "-" if row.test is None else f"{row.test.detectable:.3g}")
    glue(f"{name}_decide", row.decide or "nothing more")
