"""One convention for every figure function: data first, then ``ax`` (or ``axes``) that
defaults to a new figure, and the axes returned."""

import importlib
import inspect
import pkgutil

import matplotlib
import numpy as np
import pytest

import sgb.plots
from sgb.plots import axes_or_new, basics, subplots

matplotlib.use("agg")

# the public functions of sgb.plots.* that draw nothing (image arrays, tables, labels)
NOT_FIGURES = {"label_tiles", "stack_rows", "pair_moments", "type_boundaries", "types_label"}


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    matplotlib.pyplot.close("all")


def figure_functions():
    for info in pkgutil.iter_modules(sgb.plots.__path__):
        module = importlib.import_module(f"sgb.plots.{info.name}")
        for name, function in inspect.getmembers(module, inspect.isfunction):
            if function.__module__ == module.__name__ and not name.startswith("_"):
                yield f"{info.name}.{name}", function


def test_every_figure_function_takes_its_axes_last_defaulting_to_none():
    names = []
    for name, function in figure_functions():
        if name.split(".")[1] in NOT_FIGURES:
            continue
        names.append(name)
        last = list(inspect.signature(function).parameters.values())[-1]
        assert last.name in ("ax", "axes") and last.default is None, name
    assert len(names) >= 25  # every module's figures, not an empty loop


def test_axes_or_new_keeps_given_axes_and_makes_new_ones_otherwise():
    _, ax = subplots()
    assert axes_or_new(ax) is ax
    axes = axes_or_new(None, 1, 3)
    assert len(axes) == 3 and all(a.figure is axes[0].figure for a in axes)


def test_a_figure_function_draws_on_the_axes_given_and_returns_them():
    _, ax = subplots()
    drawn = basics.bits_bars({"a": 10.0, "b": 1e4}, "bits", ax=ax)
    assert drawn is ax and [p.get_width() for p in ax.patches] == [10.0, 1e4]
    alone = basics.bits_bars({"a": 10.0}, "bits")
    assert alone is not ax and alone.figure is not ax.figure
    np.testing.assert_allclose([p.get_width() for p in alone.patches], [10.0])
