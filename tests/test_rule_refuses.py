"""The verdict rule and the statistics behind it refuse what they cannot judge.

Every public function of ``sgb.verdicts``, ``sgb.stats`` and ``sgb.reliability`` checks its
inputs: a nan or inf, an argument out of range or a design too small or degenerate for its
test is a ``ValueError`` (a wrong type a ``TypeError``) whose message names the argument,
never a number. The property-based part draws finite tests and paper effects, for which
the verdict is one of the rule's states and agrees with its definition, and non-finite
arguments, for which every call is an error. Its examples are derandomised and no
database is kept, so every run sees the same ones.
"""

import math
import pickle

import numpy as np
import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from sgb import reliability, stats, verdicts

RULE = settings(max_examples=400, derandomize=True, database=None, deadline=None)
FEW = settings(max_examples=150, derandomize=True, database=None, deadline=None)

NAN, INF = math.nan, math.inf
A, B = [1.2, 1.4, 1.1, 1.9, 1.5], [0.2, 0.5, 0.1, 0.9, 0.4]
WELCH = stats.welch(A, B)
RETURNS = np.array([[1.0, 2.0, 3.0], [2.0, 3.0, 5.0], [0.0, 1.0, 1.0]])
SPLIT = reliability.variance_split(RETURNS)
CURVE_A = {10.0: [0.90, 0.91], 100.0: [0.80, 0.82], 700.0: [0.50, 0.52]}
CURVE_B = {10.0: [0.85, 0.86], 100.0: [0.81, 0.83], 700.0: [0.70, 0.71]}
STATES = (*verdicts.IN_DIRECTION, verdicts.CONTRADICTED, verdicts.INCONCLUSIVE)


# the reproducers of the issue, and the degenerate designs --------------------------------

REFUSED = {
    "a nan paper effect": (lambda: verdicts.verdict(WELCH, NAN), "paper"),
    "an infinite null": (lambda: verdicts.verdict(WELCH, 1.0, INF), "null"),
    "a paper effect equal to the null": (lambda: verdicts.verdict(WELCH, 0.0), "paper"),
    "a Test with a nan interval": (lambda: WELCH._replace(low=NAN, high=NAN), "low"),
    "a Test with a nan estimate": (lambda: WELCH._replace(estimate=NAN), "estimate"),
    "a Test whose low is above its high": (lambda: WELCH._replace(low=2.0, high=1.0), "low"),
    "a Test with p above 1": (lambda: WELCH._replace(p=1.5), "p"),
    "a Test with dof -inf": (lambda: WELCH._replace(dof=-INF), "dof"),
    "a Test with an infinite detectable effect": (
        lambda: WELCH._replace(detectable=INF),
        "detectable",
    ),
    "a Test of no units": (lambda: WELCH._replace(n=0), "n"),
    "fisher_from_r of a nan r": (lambda: stats.fisher_from_r(NAN, 10), "r"),
    "fisher_from_r of r = 1.5": (lambda: stats.fisher_from_r(1.5, 10), "r"),
    "fisher_from_r of r = -1": (lambda: stats.fisher_from_r(-1.0, 10), "r"),
    "fisher_from_r of 3 pairs": (lambda: stats.fisher_from_r(0.3, 3), "n"),
    "fisher_from_r of 2 pairs": (lambda: stats.fisher_from_r(0.3, 2), "n"),
    "fisher_r of constant samples": (lambda: stats.fisher_r([1.0] * 5, [2.0] * 5), "x"),
    "fisher_r of a perfect line": (lambda: stats.fisher_r(A, 2 * np.array(A)), "x and y"),
    "welch of two constant samples": (lambda: stats.welch([1.0] * 3, [2.0] * 4), "a and b"),
    "paired with a constant difference": (lambda: stats.paired([1, 2, 4], [2, 3, 5]), "a - b"),
    "one_sample of a constant": (lambda: stats.one_sample([3.0] * 4, 0.0), "values"),
    "estimate_test with no error": (lambda: stats.estimate_test("z", 1.0, 0.0, 1), "stderr"),
    "units_to_decide for a nan paper": (lambda: verdicts.units_to_decide(WELCH, NAN), "paper"),
    "units_to_decide for r = 1": (
        lambda: verdicts.units_to_decide(stats.fisher_from_r(0.2, 20), 1.0),
        "paper",
    ),
    "units_to_decide with no detectable effect": (
        lambda: verdicts.units_to_decide(WELCH._replace(detectable=NAN), 1.0),
        "detectable",
    ),
    "power_at of a test without dof": (
        lambda: stats.power_at(WELCH._replace(dof=NAN), 1),
        "dof",
    ),
    "crossings of an empty curve": (
        lambda: stats.crossings([], [], [1.0, 2.0], [0.1, 0.2]),
        "x_a",
    ),
    "crossings at x = 0": (lambda: stats.crossings([0.0, 1.0], [0, 1], [0.5, 2], [1, 0]), "x_a"),
    "crossings of unsorted x": (
        lambda: stats.crossings([1.0, 3.0], [0, 1], [2.0, 1.5, 4.0], [1, 0, 1]),
        "x_b",
    ),
    "crossings of curves that do not overlap": (
        lambda: stats.crossings([1.0, 2.0], [0, 1], [3.0, 4.0], [1, 0]),
        "x_a and x_b",
    ),
    "crossings of a y shorter than its x": (
        lambda: stats.crossings([1.0, 2.0], [0], [1.0, 2.0], [1, 0]),
        "y_a",
    ),
    "mean_ci of a constant": (lambda: stats.mean_ci([2.0, 2.0, 2.0]), "values"),
    "bootstrap_crossing of a one-point curve": (
        lambda: stats.bootstrap_crossing({1.0: [0.1, 0.2]}, CURVE_B),
        "a",
    ),
    "bootstrap_crossing at a negative seed": (
        lambda: stats.bootstrap_crossing(CURVE_A, CURVE_B, seed=-1),
        "seed",
    ),
    "between_sd_bound at an ICC bound of 1": (
        lambda: reliability.between_sd_bound(SPLIT._replace(icc_ci=(0.5, 1.0))),
        "icc_ci",
    ),
    "variance_split of identical individuals": (
        lambda: reliability.variance_split(np.tile([1.0, 2.0, 3.0], (6, 1))),
        "returns",
    ),
    "variance_split of identical episodes": (
        lambda: reliability.variance_split(np.tile([[1.0], [2.0]], (1, 3))),
        "returns",
    ),
    "variance_split at level 1.5": (lambda: reliability.variance_split(RETURNS, 1.5), "level"),
    "variance_split of one episode each": (
        lambda: reliability.variance_split(RETURNS[:, :1]),
        "returns",
    ),
    "episodes_for a nan ICC": (lambda: reliability.episodes_for(NAN), "icc"),
    "episodes_for a target of 1": (lambda: reliability.episodes_for(0.2, 1.0), "target"),
    "projected_reliability past its pole": (
        lambda: reliability.projected_reliability(-0.5, 4),
        "icc",
    ),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_each_case_is_refused_with_an_error_naming_its_argument(case):
    call, argument = REFUSED[case]
    with pytest.raises(ValueError) as error:
        call()
    assert argument in str(error.value), str(error.value)


def test_a_test_is_checked_however_it_is_built():
    """Keywords, ``_replace``, ``_make`` and pickling all pass through the checks, and a
    valid test survives them unchanged; dof, p and the detectable effect may be nan (a
    bootstrap interval has none) while the estimate and interval may not."""
    assert stats.Test(**WELCH._asdict()) == WELCH
    assert pickle.loads(pickle.dumps(WELCH)) == WELCH
    with pytest.raises(ValueError, match="high"):
        stats.Test._make([*WELCH[:3], INF, *WELCH[4:]])
    bootstrap = stats.Test("bootstrap", 60.0, 20.0, 500.0, NAN, NAN, NAN, 3)
    assert math.isnan(bootstrap.p) and verdicts.verdict(bootstrap, 1.0) == verdicts.LARGER
    with pytest.raises(TypeError, match="name"):
        stats.Test(None, *WELCH[1:])


def test_documented_limits_stay_numbers():
    """Individuals that do not differ need infinitely many episodes, and their SD between
    them is bounded by 0; curves that overlap without crossing cross nowhere."""
    assert reliability.episodes_for(-0.1) == math.inf
    assert reliability.between_sd_bound(SPLIT._replace(icc_ci=(-0.3, -0.1))) == 0.0
    assert stats.crossings([1.0, 2.0], [0.0, 0.0], [1.5, 3.0], [1.0, 1.0]) == []


# the property-based suite ------------------------------------------------------------------

FINITE = st.floats(-1e6, 1e6).map(lambda v: v + 0.0)  # -0.0 as 0.0


@st.composite
def finite_tests(draw) -> stats.Test:
    """A valid test: any finite interval, an estimate inside it, a normal or t test."""
    low, high = sorted((draw(FINITE), draw(FINITE)))
    return stats.Test(
        "drawn",
        draw(st.floats(low, high)),
        low,
        high,
        draw(st.one_of(st.floats(0.5, 1e4), st.just(INF))),
        draw(st.floats(0.0, 1.0)),
        draw(st.floats(1e-3, 1e6)),
        draw(st.integers(1, 10_000)),
    )


def near(test: stats.Test):
    """A finite effect, often exactly at an end of the interval, its estimate or 0."""
    return st.one_of(FINITE, st.sampled_from([test.low, test.high, test.estimate, 0.0]))


def definition(test: stats.Test, paper: float, null: float) -> str:
    """The rule as the module docstring words it."""
    on_paper_side = test.low > null if paper > null else test.high < null
    if on_paper_side:
        if test.low <= paper <= test.high:
            return verdicts.REPRODUCED
        nearer_null = test.high < paper if paper > null else test.low > paper
        return verdicts.SMALLER if nearer_null else verdicts.LARGER
    if paper < test.low or paper > test.high:
        return verdicts.CONTRADICTED
    return verdicts.INCONCLUSIVE


def mirrored(test: stats.Test) -> stats.Test:
    return test._replace(estimate=-test.estimate, low=-test.high, high=-test.low)


def decides_at(test: stats.Test, paper: float, null: float) -> None:
    """``units_to_decide`` is the least sample size at which the detectable effect, scaled
    as 1/sqrt(n), reaches the paper's; an effect too small for any finite one is refused."""
    effect = abs(paper - null)
    try:
        units = verdicts.units_to_decide(test, paper, null)
    except ValueError as error:
        assert "no finite sample size" in str(error) and test.detectable / effect > 1e150
        return
    assert units >= 1 and test.detectable * math.sqrt(test.n / units) <= effect * (1 + 1e-9)
    if units > 1:
        assert test.detectable * math.sqrt(test.n / (units - 1)) >= effect * (1 - 1e-9)


@RULE
@given(st.data())
def test_the_verdict_of_a_finite_test_is_a_state_of_the_rule_and_its_definition(data):
    test = data.draw(finite_tests())
    paper, null = data.draw(near(test)), data.draw(near(test))
    if paper == null:  # no side of the null to reproduce the paper on
        with pytest.raises(ValueError, match="paper"):
            verdicts.verdict(test, paper, null)
        return
    found = verdicts.verdict(test, paper, null)
    assert found in STATES and found == definition(test, paper, null)
    assert verdicts.verdict(mirrored(test), -paper, -null) == found  # no side is favoured
    inside = verdicts.paper_inside(test, paper)
    if found == verdicts.CONTRADICTED:
        assert not inside
    if found == verdicts.INCONCLUSIVE:  # neither end excluded: the null is inside too
        assert inside and test.low <= null <= test.high
        decides_at(test, paper, null)
    if test.low < test.high:
        assert 0.0 <= stats.power_at(test, paper - null) <= 1.0
    else:  # a point interval: no standard error to scale
        with pytest.raises(ValueError, match="width"):
            stats.power_at(test, paper - null)


SAMPLE = st.lists(st.floats(-1e3, 1e3).map(lambda v: round(v, 1)), min_size=2, max_size=12)


@FEW
@given(SAMPLE, SAMPLE, st.floats(0.01, 100.0))
def test_every_test_of_finite_samples_is_finite_or_a_named_refusal(a, b, paper):
    """Welch, paired and Fisher's tests of any finite samples give a finite test whose
    interval holds its estimate, whose size is 5 % and whose detectable effect has about
    80 % power, or, for a
    design they cannot test, an error naming it; the verdict is then a state."""
    calls = {
        "welch": lambda: stats.welch(a, b),
        "paired": lambda: stats.paired(a, b[: len(a)] + a[len(b) :]),
        "fisher": lambda: stats.fisher_r(a, b[: len(a)] + a[len(b) :]),
    }
    for name, call in calls.items():
        try:
            test = call()
        except ValueError as error:
            assert any(arg in str(error) for arg in ("a", "b", "x", "y")), (name, error)
            continue
        assert np.all(np.isfinite([test.estimate, test.low, test.high, test.p, test.detectable]))
        assert test.low <= test.estimate <= test.high and 0.0 <= test.p <= 1.0
        assert verdicts.verdict(test, paper) in STATES
        if name != "fisher" and test.high > test.low:
            assert stats.power_at(test, 0.0) == pytest.approx(0.05)
            assert stats.power_at(test, test.detectable) == pytest.approx(0.8, abs=0.02)


# one valid call of each public function; ``targets`` are the arguments a non-finite
# value can replace (a sequence: at a drawn position), with the name its error must give
CALLS = {
    "Test": (
        lambda **k: stats.Test(**k),
        dict(name="t", estimate=0.5, low=0.1, high=0.9, dof=4.0, p=0.2, detectable=0.3, n=5),
        {"estimate": "estimate", "low": "low", "high": "high"},
    ),
    "verdict": (verdicts.verdict, dict(test=WELCH, paper=1.0, null=0.0), None),
    "paper_inside": (verdicts.paper_inside, dict(test=WELCH, paper=1.0), None),
    "units_to_decide": (verdicts.units_to_decide, dict(test=WELCH, paper=0.1, null=0.0), None),
    "power_at": (stats.power_at, dict(test=WELCH, effect=0.5), None),
    "welch": (stats.welch, dict(a=A, b=B), None),
    "paired": (stats.paired, dict(a=A, b=B), None),
    "one_sample": (stats.one_sample, dict(values=A, null=0.0), None),
    "estimate_test": (
        stats.estimate_test,
        dict(name="z", estimate=1.0, stderr=0.5, n=1),
        {"estimate": "estimate", "stderr": "stderr"},
    ),
    "fisher_r": (stats.fisher_r, dict(x=A, y=B), None),
    "fisher_from_r": (stats.fisher_from_r, dict(r=0.3, n=10), {"r": "r"}),
    "sem": (stats.sem, dict(values=A), None),
    "mean_ci": (stats.mean_ci, dict(values=A, level=0.9), None),
    "crossings": (
        stats.crossings,
        dict(x_a=[1.0, 10.0, 100.0], y_a=[0.0, 1.0, 2.0], x_b=[2.0, 50.0], y_b=[1.0, 0.5]),
        None,
    ),
    "bootstrap_crossing": (
        lambda a, b, level: stats.bootstrap_crossing(a, b, draws=20, level=level),
        dict(a=CURVE_A, b=CURVE_B, level=0.9),
        None,
    ),
    "variance_split": (reliability.variance_split, dict(returns=RETURNS, level=0.9), None),
    "projected_reliability": (
        reliability.projected_reliability,
        dict(icc=0.2, episodes=4),
        {"icc": "icc", "episodes": "episodes"},
    ),
    "episodes_for": (reliability.episodes_for, dict(icc=0.2, target=0.8), None),
    "between_sd_bound": (
        lambda icc_high, within: reliability.between_sd_bound(
            SPLIT._replace(icc_ci=(0.1, icc_high), within_var=within)
        ),
        dict(icc_high=0.5, within=1.0),
        {"icc_high": "icc_ci", "within": "within_var"},
    ),
}


def corrupt(value, bad: float, where: int):
    """``value`` with a non-finite entry: itself if a number, else at position ``where``
    of a sequence, an array or every sequence of a mapping."""
    if isinstance(value, float | int):
        return bad
    if isinstance(value, dict):
        return {x: corrupt(v, bad, where) for x, v in value.items()}
    array = np.array(value, dtype=np.float64)
    array.flat[where % array.size] = bad
    return array


def non_finite_targets(which: str) -> dict[str, str]:
    """The arguments of ``which`` that can be non-finite, each with the name it is given
    in an error: those listed, else every number and sequence of numbers."""
    _, valid, targets = CALLS[which]
    if targets is not None:
        return targets
    return {name: name for name, v in valid.items() if not isinstance(v, stats.Test | str)}


@RULE
@given(
    st.sampled_from(sorted(CALLS)),
    st.data(),
    st.sampled_from([NAN, INF, -INF]),
    st.integers(0, 20),
)
def test_any_non_finite_argument_is_an_error_naming_it(which, data, bad, where):
    call, valid, _ = CALLS[which]
    argument, named = data.draw(st.sampled_from(sorted(non_finite_targets(which).items())))
    event(which)
    args = {**valid, argument: corrupt(valid[argument], bad, where)}
    with pytest.raises(ValueError) as error:
        out = call(**args)
        pytest.fail(f"{which}({argument}={bad}) returned {out!r}")
    assert named in str(error.value), str(error.value)
