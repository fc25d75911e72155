"""Stop training on divergence: a blown-up or non-finite loss or parameter is an error,
never a result.

A ``Guard`` watches one training run. It stops it (``TrainingDiverged``, naming the step
and the value) at the first loss that is not finite or whose magnitude exceeds
``BLOWUP_FACTOR`` times that of the run's first loss (at least 1: a loss that starts
near zero may still grow to ``BLOWUP_FACTOR``), at the first fit error above a bound it
is given, and at a non-finite parameter. Its message names the likely cause from what it
checks when it stops (``likely_cause``): nan or inf in the data, labels out of range, an
empty set, a spread parameter ``rho`` beyond the range of ``sgb.genome.softplus``, and
else the learning rate.

The thresholds are far from every run of the committed results: a loss can only trip
the guard beyond ``BLOWUP_FACTOR`` = 1e4 in magnitude, and the final losses of their
supervised runs are at most 4.4 in magnitude, the DGB's fit errors (dimensionless, in
units of the p-net's initial weight scale) at most 0.04 (``tests/test_robustness.py``
checks both); the PPO loss of a trained Ant or HalfCheetah agent is within 3x of that
of a fresh one (measured on committed checkpoints, vanilla and 16 types).
"""

import math
from collections.abc import Callable, Mapping
from typing import Any

import jax
import numpy as np

BLOWUP_FACTOR = 1e4
FIT_BOUND = 1e4
RHO_LIMIT = 88.0  # sgb.genome.SOFTPLUS_LIMIT: where float32's exp(rho) stops being finite
LEARNING_RATE = "the learning rate, probably too large: try a smaller one"


def learning_rate_cause(name: str) -> str:
    """The cause "learning rate" for the setting ``name`` (e.g. ``gnet_learning_rate``)."""
    return f"the learning rate {name}, probably too large: try a smaller one"


class TrainingDiverged(FloatingPointError):
    """Training blew up: a loss or a parameter became non-finite or far too large; the
    message names the step, the value and the likely cause."""


def likely_cause(
    *,
    data: Mapping[str, Any] | None = None,
    labels: Any = None,
    num_classes: int | None = None,
    params: Any = None,
) -> str:
    """What most likely made training diverge, from the checks this makes in order: an
    empty or non-finite array of ``data``, ``labels`` outside [0, ``num_classes``), a
    ``rho`` leaf of ``params`` above ``RHO_LIMIT`` (not nan: training made that); else the
    learning rate."""
    for name, values in (data or {}).items():
        values = np.asarray(values)
        if values.size == 0:
            return f"an empty set: {name} holds no examples"
        if values.dtype.kind == "f" and not np.isfinite(values).all():
            return f"nan or inf in the data: {name} holds {np.sum(~np.isfinite(values))} of them"
    if labels is not None and num_classes is not None:
        y = np.asarray(labels)
        if y.size and (y.min() < 0 or y.max() >= num_classes):
            return (
                f"labels out of range: they run from {y.min()} to {y.max()}, outside "
                f"[0, {num_classes})"
            )
    if params is not None:
        # a rho beyond the limit (inf included); one that is nan came from the step itself
        rho = [
            float(np.max(values, initial=-np.inf, where=~np.isnan(values)))
            for path, leaf in jax.tree_util.tree_leaves_with_path(params)
            if "rho" in jax.tree_util.keystr(path)
            for values in [np.asarray(leaf, dtype=np.float64)]
        ]
        if rho and max(rho) > RHO_LIMIT:
            return (
                f"rho overflow: a spread parameter rho reached {max(rho):.4g}, beyond "
                f"{RHO_LIMIT:g} where sigma = softplus(rho) saturates; start from a smaller "
                "rho_init or a smaller learning rate"
            )
    return LEARNING_RATE


class Guard:
    """The divergence checks of one training run.

    ``what`` names its loss in messages; ``cause()`` is called only when the guard stops
    the run, to name the likely cause (default: the learning rate). ``start`` is the first
    loss it was given.
    """

    def __init__(
        self,
        what: str = "loss",
        cause: Callable[[], str] | None = None,
        factor: float = BLOWUP_FACTOR,
    ) -> None:
        self.what = what
        self.cause = cause or (lambda: LEARNING_RATE)
        self.factor = factor
        self.start: float | None = None

    def _stop(self, what: str, value: Any, step: int, why: str) -> None:
        try:
            cause = self.cause()
        except Exception:  # a diagnosis that fails must not hide the divergence itself
            cause = LEARNING_RATE
        raise TrainingDiverged(
            f"training diverged: {what} = {value} at step {step} ({why}); likely cause: "
            f"{cause} (no result is reported from these parameters)"
        )

    def loss(self, value: float, step: int) -> None:
        """Check the loss after ``step`` updates: finite, and within ``factor`` times the
        magnitude of the first loss (at least 1)."""
        value = float(value)
        if not math.isfinite(value):
            self._stop(self.what, value, step, "not finite")
        if self.start is None:
            self.start = value
        limit = self.factor * max(abs(self.start), 1.0)
        if abs(value) > limit:
            self._stop(
                self.what,
                value,
                step,
                f"beyond {self.factor:g} x the magnitude of its start {self.start:.4g}",
            )

    def losses(self, values: Any, first_step: int, step_size: int = 1) -> None:
        """``loss`` of each of ``values``, taken at steps ``first_step``, ``+ step_size``..."""
        for i, value in enumerate(np.asarray(values).ravel()):
            self.loss(float(value), first_step + i * step_size)

    def bound(self, what: str, value: float, step: int, limit: float = FIT_BOUND) -> None:
        """Check that ``value`` (e.g. a fit error) is finite and at most ``limit``."""
        value = float(value)
        if not value <= limit:
            self._stop(what, value, step, "not finite" if math.isnan(value) else f"above {limit:g}")

    def params(self, params: Any, step: int) -> None:
        """Check that every parameter leaf is finite after ``step`` updates."""
        for path, leaf in jax.tree_util.tree_leaves_with_path(params):
            values = np.asarray(leaf)
            if not np.all(np.isfinite(values)):
                bad = values[~np.isfinite(values)].flat[0]
                self._stop(f"parameter {jax.tree_util.keystr(path)}", bad, step, "not finite")


def check_loss(value: float, step: int, what: str = "loss") -> None:
    """Raise ``TrainingDiverged`` if ``value`` (the loss after ``step`` updates) is nan or inf."""
    if not math.isfinite(value):
        Guard(what).loss(value, step)


def check_params(params: Any, step: int) -> None:
    """Raise ``TrainingDiverged`` if any parameter leaf holds a nan or inf after ``step``."""
    Guard().params(params, step)


def check_trajectory(
    values: Mapping[str, Any], *, trained: tuple[str, ...] = (), what: str = "trajectory"
) -> None:
    """Check recorded trajectories, each (..., steps + 1) with step t on the last axis:
    every value finite, and every ``trained`` one within ``BLOWUP_FACTOR`` times the
    magnitude of its start (at least 1). Raises ``TrainingDiverged`` naming the first step
    where one is not."""
    first: tuple[int, str, float] | None = None
    for name, array in values.items():
        array = np.asarray(array, dtype=np.float64)
        bad = ~np.isfinite(array)
        if name in trained:
            start = np.maximum(np.abs(array[..., :1]), 1.0)
            with np.errstate(invalid="ignore"):
                bad |= np.abs(array) > BLOWUP_FACTOR * start
        if bad.any():
            step = int(np.nonzero(bad.reshape(-1, array.shape[-1]).any(axis=0))[0][0])
            if first is None or step < first[0]:
                first = (step, name, float(array[..., step][bad[..., step]].flat[0]))
    if first is not None:
        step, name, value = first
        why = (
            f"beyond {BLOWUP_FACTOR:g} x the magnitude of its start (at least 1)"
            if math.isfinite(value)
            else "not finite"
        )
        Guard()._stop(f"{what} {name}", value, step, why)
