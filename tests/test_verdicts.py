"""``sgb.verdicts``: the rule finds a true effect, rejects a null, flags an underpowered
design, and says how much of a reproduced direction holds."""

import numpy as np

from sgb import stats, verdicts


def test_the_rule_finds_a_true_effect_rejects_a_null_and_flags_an_underpowered_design():
    rng = np.random.default_rng(2)
    true = stats.welch(rng.normal(1.0, 0.5, 30), rng.normal(0.0, 0.5, 30))
    assert verdicts.verdict(true, 1.0) == verdicts.REPRODUCED
    assert verdicts.paper_inside(true, 1.0)
    # a null effect is (almost) never called reproduced, and with a large sample it is
    # called contradicted
    calls = [
        verdicts.verdict(stats.welch(rng.normal(0, 1, 10), rng.normal(0, 1, 10)), 1.0)
        for _ in range(1000)
    ]
    in_direction = sum(c in verdicts.IN_DIRECTION for c in calls)
    assert in_direction / 1000 < 0.04  # one side of a 5 % test: 2.5 %
    big_null = stats.welch(rng.normal(0, 1, 400), rng.normal(0, 1, 400))
    assert verdicts.verdict(big_null, 1.0) == verdicts.CONTRADICTED
    # an effect of the paper's size measured with too few units: neither side excluded
    small = stats.welch(np.array([0.3, 1.3, 2.3]), np.array([0.0, 1.0, 2.0]))
    assert verdicts.verdict(small, 0.3) == verdicts.INCONCLUSIVE
    assert verdicts.units_to_decide(small, 0.3) > 3
    # the paper's side is negative: the rule mirrors
    assert verdicts.verdict(stats.welch(rng.normal(-1, 0.5, 30), rng.normal(0, 0.5, 30)), -1.0) == (
        verdicts.REPRODUCED
    )


def test_the_rule_says_how_much_a_reproduced_direction_holds():
    """With the paper's effect 1 (or -1): a true effect of 0.3 measured well enough is the
    paper's direction at a smaller size; 2 a larger; 1 the paper's; mirrored below 0."""
    rng = np.random.default_rng(5)

    def measured(effect: float):
        return stats.welch(rng.normal(effect, 0.5, 200), rng.normal(0.0, 0.5, 200))

    for sign in (1.0, -1.0):
        assert verdicts.verdict(measured(0.3 * sign), sign) == verdicts.SMALLER
        assert verdicts.verdict(measured(2.0 * sign), sign) == verdicts.LARGER
        assert verdicts.verdict(measured(1.0 * sign), sign) == verdicts.REPRODUCED


def test_an_effect_larger_than_the_setting_allows_is_not_testable_whatever_the_interval():
    """With room for 0.2 against the paper's 0.3, a measured null (else contradicted) and
    a measured 0.3 (else reproduced) both get the no-room state; with room for 0.5, the
    rule is the usual one; mirrored for a negative paper effect."""
    rng = np.random.default_rng(8)
    for sign in (1.0, -1.0):
        null = stats.welch(rng.normal(0.0, 0.1, 200), rng.normal(0.0, 0.1, 200))
        paper = stats.welch(rng.normal(0.3 * sign, 0.1, 200), rng.normal(0.0, 0.1, 200))
        for test, usual in ((null, verdicts.CONTRADICTED), (paper, verdicts.REPRODUCED)):
            assert verdicts.verdict(test, 0.3 * sign) == usual
            assert verdicts.verdict(test, 0.3 * sign, room=0.5) == usual
            assert verdicts.verdict(test, 0.3 * sign, room=0.2) == verdicts.NO_ROOM
