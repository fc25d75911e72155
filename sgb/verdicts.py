"""The one rule that turns a test (``sgb.stats.Test``: an effect, its 95 % interval and the
effect detectable at 80 % power) into a verdict.

The rule, for a claim whose paper effect is ``paper`` against a null ``null`` (no effect):

- **reproduced**: the interval excludes the null, on the paper's side of it, and holds the
  paper's effect (or the effect that stands in for it);
- **reproduced in direction, smaller (larger) than the effect compared**: the interval
  excludes the null on the paper's side, and the paper's effect (or its stand-in) on the
  far (near) side: the direction holds, the size does not;
- **contradicted**: otherwise, if the interval excludes the paper's effect;
- **inconclusive at this budget**: neither; the budget that would decide is the sample
  size at which the detectable effect shrinks to the paper's (``units_to_decide``);
- **not testable at this budget**: whatever the interval, where the largest effect the
  setting leaves room for (``room``: the distance from the arm that should lead to a floor
  or a ceiling, in the paper's direction) is below the paper's: no outcome could then show
  the paper's effect, nor refute it;
- **not testable here**: no run here can test the claim (a reason is given instead).
"""

import math

from scipy import stats as scipy_stats

from sgb import validation
from sgb.stats import LEVEL, POWER, Test

REPRODUCED = "reproduced"
# smaller or larger than the effect the row compares: the paper's, or its stand-in
SMALLER = "reproduced in direction, smaller than the effect compared"
LARGER = "reproduced in direction, larger than the effect compared"
CONTRADICTED = "contradicted"
INCONCLUSIVE = "inconclusive at this budget"
NO_ROOM = "not testable at this budget"
NOT_TESTABLE = "not testable here"
IN_DIRECTION = (REPRODUCED, SMALLER, LARGER)  # the paper's direction holds
VERDICTS = (*IN_DIRECTION, CONTRADICTED, INCONCLUSIVE, NO_ROOM, NOT_TESTABLE)


def _effect(test: Test, paper: float, null: float) -> tuple[float, float]:
    """``paper`` and ``null`` checked against ``test``: finite, and apart (the rule needs
    the paper's side of the null)."""
    validation.instance("test", test, Test)
    paper, null = validation.real("paper", paper), validation.real("null", null)
    if paper == null:
        raise ValueError(f"paper must differ from null ({null!r}): an effect of none has no side")
    return paper, null


def verdict(test: Test, paper: float, null: float = 0.0, room: float | None = None) -> str:
    """The rule of the module docstring: ``REPRODUCED``, ``SMALLER``, ``LARGER``,
    ``CONTRADICTED``, ``INCONCLUSIVE``, or with ``room`` (the largest effect the setting
    allows, in the paper's direction from the null) below the paper's, ``NO_ROOM``."""
    paper, null = _effect(test, paper, null)
    if room is not None and validation.real("room", room) < abs(paper - null):
        return NO_ROOM
    if (paper > null and test.low > null) or (paper < null and test.high < null):
        if paper_inside(test, paper):
            return REPRODUCED
        beyond = test.low > paper if paper > null else test.high < paper
        return LARGER if beyond else SMALLER
    if not test.low <= paper <= test.high:
        return CONTRADICTED
    return INCONCLUSIVE


def paper_inside(test: Test, paper: float) -> bool:
    """Whether the paper's effect lies inside the test's interval."""
    validation.instance("test", test, Test)
    return test.low <= validation.real("paper", paper) <= test.high


def units_to_decide(test: Test, paper: float, null: float = 0.0) -> int:
    """The sample size (per group, in the test's units) at which the detectable effect
    equals the paper's, scaling the standard error as 1/sqrt(n) (for r, through Fisher's
    z, where the paper's r must lie in (-1, 1))."""
    paper, null = _effect(test, paper, null)
    effect = abs(paper - null)
    if test.name == "Fisher z":
        if effect >= 1:
            raise ValueError(f"paper must be a correlation in (-1, 1), got {paper!r}")
        crit = scipy_stats.norm.ppf(0.5 + LEVEL / 2) + scipy_stats.norm.ppf(POWER)
        units = _squared(crit / math.atanh(effect)) + 3
    elif math.isnan(test.detectable):
        raise ValueError(f"test has no detectable effect to scale ({test.name})")
    else:
        units = test.n * _squared(test.detectable / effect)
    if not math.isfinite(units):
        raise ValueError(f"no finite sample size detects paper = {paper!r} with this test")
    return math.ceil(units)


def _squared(x: float) -> float:
    """``x * x``, ``inf`` where it overflows (``x ** 2`` raises there)."""
    return x * x
