"""Stop training on divergence: a non-finite loss or parameter is an error, never a result."""

import math
from typing import Any

import jax
import numpy as np


class TrainingDiverged(FloatingPointError):
    """Training produced a non-finite loss or parameter; the message names the step and value."""


def check_loss(value: float, step: int, what: str = "loss") -> None:
    """Raise ``TrainingDiverged`` if ``value`` (the loss after ``step`` updates) is nan or inf."""
    if not math.isfinite(value):
        raise TrainingDiverged(
            f"training diverged: {what} = {value} at step {step}; "
            "try a smaller learning rate (no result is reported from these parameters)"
        )


def check_params(params: Any, step: int) -> None:
    """Raise ``TrainingDiverged`` if any parameter leaf holds a nan or inf after ``step``."""
    for path, leaf in jax.tree_util.tree_leaves_with_path(params):
        values = np.asarray(leaf)
        if not np.all(np.isfinite(values)):
            bad = values[~np.isfinite(values)].flat[0]
            raise TrainingDiverged(
                f"training diverged: parameter {jax.tree_util.keystr(path)} = {bad} at step "
                f"{step}; try a smaller learning rate (no result is reported from these parameters)"
            )
