"""The scorecard at a glance (``sgb.scorecard``): every committed row lands under one claim,
a claim's headline is its largest budget's first row, the counts add up, and numbers are
printed to the precision their interval carries."""

import dataclasses
import re

import numpy as np
import pytest

from sgb import claims, gather, scorecard, stats, verdicts
from sgb.experiments import regime as regime_runs
from sgb.paths import committed_results


def _row(key: str, verdict: str, estimate: float = 1.0, setting: str = "s") -> claims.Row:
    test = stats.estimate_test("Monte Carlo z", estimate, 0.5, 10)
    claim = claims.CLAIMS.get(key) or claims.Claim(key, "Figure 9", "a claim", "p", "e", 1, "", "")
    return claims.Row(claim, setting, 1.0, "", test, "b", verdict, "")


def test_every_committed_row_lands_under_one_claim_and_the_counts_add_up():
    rows = gather.scorecard(committed_results())
    lines = scorecard.claim_lines(rows)
    assert sorted(id(r) for line in lines for r in line.rows) == sorted(id(r) for r in rows)
    assert sum(scorecard.counts(rows).values()) == len(rows)
    page = scorecard.html(rows)
    assert page.count('class="sgb-claim"') == len(lines)
    # one badge per claim line and one per row in the folded tables
    assert page.count('class="sgb-badge"') == len(lines) + len(rows)
    widths = [int(w) for w in re.findall(r'<col style="width:(\d+)%">', page)]
    assert len(widths) == 5 and sum(widths) == 100
    summary = scorecard.summary_text(rows)
    assert summary.startswith(f"{len(rows)} rows: ")
    for verdict, n in scorecard.counts(rows).items():
        assert f"**{n}** {scorecard.SHORT.get(verdict, verdict)}" in summary


def test_a_claims_headline_is_the_first_row_of_its_largest_budget():
    rows = [
        _row("fig2.sgb_better_high", verdicts.INCONCLUSIVE, setting="5 epochs"),
        _row("fig2.full.sgb_better_high", verdicts.CONTRADICTED, setting="full, 200x"),
        _row("fig2.full.sgb_better_high", verdicts.REPRODUCED, setting="full, 400x"),
        _row("fig2.dgb_better_low", verdicts.REPRODUCED),
    ]
    lines = scorecard.claim_lines(rows)
    assert [line.headline.key for line in lines] == [
        "fig2.dgb_better_low",
        "fig2.full.sgb_better_high",
    ]
    assert lines[1].headline.setting == "full, 200x" and len(lines[1].rows) == 3
    assert scorecard.counts(rows) == {
        verdicts.REPRODUCED: 2,
        verdicts.SMALLER: 0,
        verdicts.LARGER: 0,
        verdicts.CONTRADICTED: 1,
        verdicts.INCONCLUSIVE: 1,
        verdicts.NO_ROOM: 0,
        verdicts.NOT_TESTABLE: 0,
    }
    with pytest.raises(ValueError, match="belongs to no claim"):
        scorecard.claim_lines([_row("fig9.unknown", verdicts.REPRODUCED)])


@pytest.mark.parametrize(
    ("estimate", "low", "high", "text"),
    [
        (11.2, 0.966, 21.4, "11 [1, 21]"),
        (0.1234, 0.1, 0.15, "0.123 [0.100, 0.150]"),
        (-18.63, -19.84, -17.41, "\u221218.6 [\u221219.8, \u221217.4]"),
        (6989.0, 5200.4, 8800.0, "6,989 [5,200, 8,800]"),
    ],
)
def test_numbers_carry_the_precision_of_their_interval(estimate, low, high, text):
    assert scorecard.interval_text(estimate, low, high) == text
    # two significant digits of the width survive the rounding
    numbers = re.findall(r"[\u2212\d.,]*\d", text)
    shown = [float(x.replace("\u2212", "-").replace(",", "")) for x in numbers]
    assert np.isclose(shown[2] - shown[1], high - low, rtol=0.1)


def test_every_row_says_which_effect_it_compares_and_where_it_comes_from():
    """A row whose effect stands in for a direction says so in words beside the number; a
    row with the paper's own number says it is the paper's; the page shows both."""
    rows = gather.scorecard(committed_results())
    stand_in = next(r for r in rows if r.basis and r.paper_effect is not None)
    assert stand_in.compared.endswith(f"({stand_in.basis})")
    own = dataclasses.replace(stand_in, paper_effect=0.25, basis="")
    assert own.compared == "0.25 (the paper's)"
    page = scorecard.html(rows)
    assert "effect compared" in page
    assert scorecard.html_escape.escape(stand_in.compared) in page


def test_holm_corrects_within_each_figure_and_the_page_names_the_survivors():
    """Figure 3C and 3D are one family; each row's corrected p is Holm's over its family's
    p alone; the page counts the reproduced rows whose corrected p stays under 0.05."""
    rows = gather.scorecard(committed_results())
    adjusted = scorecard.holm_p(rows)
    figure3 = [i for i, r in enumerate(rows) if r.figure.startswith("Figure 3")]
    assert {rows[i].figure for i in figure3} >= {"Figure 3C", "Figure 3D"}
    expected = stats.holm([rows[i].test.p for i in figure3])
    np.testing.assert_allclose([adjusted[i] for i in figure3], expected)
    pairs = list(zip(rows, adjusted, strict=True))
    assert all(q >= r.test.p for r, q in pairs if r.test and not np.isnan(q))
    reproduced = [q for r, q in pairs if r.verdict in verdicts.IN_DIRECTION]
    survive = sum(q < 0.05 for q in reproduced)
    assert f"**{survive} of the {len(reproduced)}**" in scorecard.holm_text(rows)


def test_a_verdict_below_the_papers_budget_says_how_far_below():
    """Figure 3 at 2M steps is at 4 % of the paper's 5 x 10^7 steps, and its line on the
    page says so under the badge; the authors' own 49,152,000 steps count as the paper's
    budget; a theorem has no budget of the paper's to fall short of."""
    rows = gather.scorecard(committed_results())
    fig3 = next(r for r in rows if r.key == "fig3.fall_16.ant")
    assert fig3.amount == 2_000_000 and fig3.share == pytest.approx(0.04)
    assert fig3.below_budget == "at 4 % of the paper's budget (steps)"
    assert fig3.budget_text.endswith("(at 4 % of the paper's budget (steps))")
    regime = dataclasses.replace(fig3, amount=49_152_000)
    assert regime.below_budget == "" and regime.budget_text == regime.budget
    theorem = next(r for r in rows if r.family.startswith("Theorem"))
    assert theorem.paper_budget == claims.NO_PAPER_BUDGET and theorem.share is None
    page = scorecard.html([fig3])
    below = scorecard.html_escape.escape(fig3.below_budget)
    assert f'<br><small style="color:#555">{below}</small>' in page
    assert scorecard.html_escape.escape(fig3.paper_budget.text) in page


def test_the_page_places_every_claim_of_the_table_once():
    """Every claim of ``claims.CLAIMS`` is on one line of the page, and a line names no
    claim the table lacks; a claim whose effect each setting sets is refused without it."""
    placed = [key for keys in scorecard.CLAIMS for key in keys]
    assert sorted(placed) == sorted(claims.CLAIMS)
    test = stats.estimate_test("Monte Carlo z", 1.0, 0.5, 10)
    with pytest.raises(ValueError, match="fig4e.r_legs"):
        claims.judge("fig4e.r_legs", "s", test, "b")
    row = claims.judge("fig4e.r_legs", "s", test, "b", paper_effect=0.5, basis="half")
    assert (row.paper_effect, row.basis, row.statement) == (
        0.5,
        "half",
        claims.CLAIMS["fig4e.r_legs"].statement,
    )


def test_figure_3c_at_the_papers_budget_heads_its_claims_once_two_seeds_per_arm_land():
    """Synthetic regime runs with a known fall (16 types at an eighth of vanilla, 128 types
    at vanilla's level): the fall is reproduced, and its row heads the claim, above the
    2M-step row; with one seed per arm there is no row."""
    rng = np.random.default_rng(0)
    levels = {None: 7000.0, 128: 7000.0, 16: 900.0}
    runs = [
        {
            "cell_types": k,
            "seed": s,
            "genome": "authors",
            "final_return": level + rng.normal(0, 300),
        }
        for s in range(3)
        for k, level in levels.items()
    ]

    def regime_rows(runs: list[dict]) -> list[claims.Row]:
        """``regime_rows`` of ``runs``, each completed to a run of the regime's file."""
        played = {"eval_steps": [0, 1], "train_steps_per_s": 1e4, "wall_time_s": 1.0}
        records = [
            regime_runs.RegimeRun.model_validate(
                r
                | played
                | {
                    "last_two_return": r["final_return"],
                    "eval_returns": [0.0, r["final_return"]],
                    "authors_scale": r["final_return"] / 8000,
                }
            )
            for r in runs
        ]
        return regime_runs.regime_rows(records, 50_000_000)

    rows = regime_rows(runs)
    by_key = {r.key: r for r in rows}
    fall = by_key["fig3.fall_16.regime.ant"]
    # a fall of about 0.87 of vanilla, measured to within 0.2, is larger than the 0.3 stand-in
    assert fall.verdict == verdicts.LARGER and fall.test.low > 0.7
    assert "50M steps" in fall.budget
    assert regime_rows([r for r in runs if r["seed"] == 0]) == []
    no_second_16 = [r for r in runs if r["seed"] == 0 or r["cell_types"] != 16]
    (level,) = regime_rows(no_second_16)
    assert level.key == "fig3.level_128.regime.ant" and "16 types 1" in level.budget
    two_million = _row("fig3.fall_16.ant", verdicts.REPRODUCED)
    (line,) = [x for x in scorecard.claim_lines([two_million, fall]) if len(x.rows) == 2]
    assert line.headline is fall
