"""What the chapters share: values glued into their prose, and the package's own code.

``glue(name, text)`` stores ``text`` (markdown) under ``name`` for the chapters'
``{glue:md}`name``` roles, so that no number or verdict in the prose is typed by hand;
``glue_all(texts)`` glues a mapping of them (``sgb.prose`` computes them from results).
Where the book's builder (myst-nb) is not installed, as on Colab, it does nothing: only
the built book reads glued values. ``show_source(obj)`` displays the source of a package
function or class as the book is built, so that the code a chapter explains is the code
that runs and cannot drift from it.
"""

import inspect
import textwrap
from collections.abc import Mapping


def source(obj: object) -> str:
    """The source code of a function, method or class of the package, dedented."""
    return textwrap.dedent(inspect.getsource(obj))


def show_source(*objs: object) -> None:
    """Display the source of each of ``objs`` as a Python code block (plain text outside
    a notebook)."""
    code = "\n\n".join(source(obj) for obj in objs)
    try:
        from IPython.display import Code, display
    except ImportError:
        print(code)
        return
    display(Code(code, language="python"))


def glue(name: str, text: str) -> None:
    """Store ``text`` as markdown under ``name`` for ``{glue:md}`` roles (not shown here)."""
    try:
        from IPython.display import Markdown
        from myst_nb import glue as myst_glue
    except ImportError:
        return
    myst_glue(name, Markdown(text), display=False)


def glue_all(texts: Mapping[str, str]) -> None:
    """``glue`` each text of ``texts`` (glue name -> markdown), e.g. an ``sgb.prose``
    mapping."""
    for name, text in texts.items():
        glue(name, text)
