"""What the chapters share: values glued into their prose, and the package's own code.

``glue(name, text)`` stores ``text`` (markdown) under ``name`` for the chapters'
``{glue:md}`name``` roles, so that no number or verdict in the prose is typed by hand;
``glue_all(texts)`` glues a mapping of them (``sgb.prose`` computes them from results).
Where the book's builder (myst-nb) is not installed, as on Colab, it does nothing: only
the built book reads glued values. ``show_source(obj)`` displays the lines of a package
function or class that define its method (``defining_source``: no docstrings, no argument
checks) as the book is built, so that the code a chapter explains is the code that runs
and cannot drift from it. ``table(frame, caption)`` shows a table as a reader reads it.
"""

import ast
import html
import inspect
import math
import numbers
import textwrap
from collections.abc import Mapping, Sequence

import pandas as pd


def source(obj: object) -> str:
    """The source code of a function, method or class of the package, dedented."""
    return textwrap.dedent(inspect.getsource(obj))


def _is_docstring(node: ast.stmt) -> bool:
    return (
        isinstance(node, ast.Expr)
        and isinstance(node.value, ast.Constant)
        and isinstance(node.value.value, str)
    )


def _is_check(node: ast.stmt) -> bool:
    """An argument check: a call of ``validation.*`` (alone or assigned), an ``if`` that
    only raises, or a loop of checks."""
    value = node.value if isinstance(node, ast.Expr | ast.Assign) else None
    if isinstance(value, ast.Call):
        func = value.func
        return isinstance(func, ast.Attribute) and getattr(func.value, "id", "") == "validation"
    if isinstance(node, ast.If) and not node.orelse:
        return all(isinstance(s, ast.Raise) or _is_check(s) for s in node.body)
    if isinstance(node, ast.For) and not node.orelse:
        return all(_is_check(s) for s in node.body)
    return False


def defining_source(obj: object) -> str:
    """``source(obj)`` without what does not define the method: docstrings and argument
    checks (``_is_check``); the lines kept are the file's, in order, comments included."""
    text = source(obj)
    dropped: set[int] = set()
    definitions = ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef
    for node in ast.walk(ast.parse(text)):
        for field in ("body", "orelse"):
            statements = getattr(node, field, None)
            if not isinstance(statements, list):  # a lambda's or an expression's body
                continue
            for i, statement in enumerate(statements):
                docstring = isinstance(node, definitions) and i == 0 and _is_docstring(statement)
                if docstring or _is_check(statement):
                    dropped.update(range(statement.lineno, statement.end_lineno + 1))
    lines = text.splitlines()
    return "\n".join(line for n, line in enumerate(lines, start=1) if n not in dropped) + "\n"


def show_source(*objs: object) -> None:
    """Display the lines that define each of ``objs`` (``defining_source``) as a Python
    code block (plain text outside a notebook)."""
    code = "\n\n".join(defining_source(obj) for obj in objs)
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


def number_text(x: object) -> str:
    """A table cell as a reader reads it: integers whole, with thousands separated; other
    numbers to three significant figures (whole from 100 on); text as it is; "-" for none."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        return str(x)
    if float(x).is_integer() and abs(x) >= 1:
        return f"{int(x):,}"
    if abs(x) >= 100:
        return f"{x:,.0f}"
    return f"{x:.3g}"


def p_text(p: object) -> str:
    """A p-value as a reader reads it: "< 0.001" below 0.001, else three decimals."""
    if p is None or (isinstance(p, float) and math.isnan(p)):
        return "-"
    return "< 0.001" if p < 0.001 else f"{p:.3f}"


def table(frame: pd.DataFrame, caption: str, p_columns: Sequence[str] = ()):
    """``frame`` as the book shows a table: its ``caption`` above, no index column, every
    cell through ``number_text``, the columns named in ``p_columns`` through ``p_text``,
    and no text cut short (a pandas ``Styler``)."""
    missing = [c for c in p_columns if c not in frame.columns]
    if missing:
        raise ValueError(f"p_columns {missing} are not columns of the table: {list(frame)}")

    def shown(text_of):  # a Styler's formatter's text goes into the HTML as it is
        return lambda x: html.escape(text_of(x))

    formats = {c: shown(p_text if c in p_columns else number_text) for c in frame.columns}
    caption_style = {"selector": "caption", "props": "caption-side: top; text-align: left;"}
    return (
        frame.style.hide(axis="index")
        .format(formats)
        .set_caption(html.escape(caption))
        .set_table_styles([caption_style])
    )
