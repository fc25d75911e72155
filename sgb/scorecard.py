"""The scorecard at a glance: the counts by verdict, then one line per claim of the paper
with its rows at every setting and budget folded under it.

``CLAIMS`` lists the paper's claims in its order, each by the ``sgb.claims`` keys that
test it, the largest budget first: a claim's headline is the first row of its first key
that has rows, and gives the line its figure and words. ``counts(rows)`` counts the
verdicts; ``claim_lines(rows)`` groups the rows by claim; ``html(rows)`` renders them as
one table that fits the book's content width (a fixed layout, the verdict in its own
column), each claim's rows in a ``<details>`` under it. Numbers are printed to the
precision of their interval (``interval_text``).
"""

import html as html_escape
import math
from collections import Counter
from dataclasses import dataclass

from sgb import stats, verdicts
from sgb.book import p_text
from sgb.claims import Row

# Each claim's keys in ``sgb.claims.CLAIMS``, the largest budget first; the claims in the
# paper's order.
CLAIMS: tuple[tuple[str, ...], ...] = (
    ("title.variability.regime", "title.variability"),
    ("fig2.dgb_better_low",),
    ("fig2.full.sgb_better_high", "fig2.sgb_better_high"),
    ("fig2.monotone",),
    ("fig2.sgb_declines_slowly",),
    ("fig2.kl_explains_low",),
    ("fig2.full.crossover", "fig2.crossover"),
    ("fig2.cifar",),
    ("fig3.level_128.regime.ant", "fig3.level_128.ant", "fig3.level_128.halfcheetah"),
    ("fig3.fall_16.regime.ant", "fig3.fall_16.ant", "fig3.fall_16.halfcheetah"),
    ("fig3.shape_32.regime.ant", "fig3.shape_32.ant", "fig3.shape_32.halfcheetah"),
    ("ch5.typing_explains_fall",),
    ("fig4e.r_legs",),
    ("fig4f.r_terrain",),
    ("fig5.population_beats_mean",),
    ("abstract.population_beats_mean_supervised",),
    ("abstract.larger_networks",),
    ("theorem.A.1",),
    ("theorem.A.2",),
    ("theorem.A.2.saddle",),
    ("theorem.A.3",),
    ("theorem.A.4",),
    ("ch6.evolution_stochastic_helps",),
    ("ch6.hedging_geometric",),
    ("ch6.hedging_survival",),
    ("ch6.hedging_lineage",),
    ("ch6.innate_start_rl",),
    ("ch6.innate_start_supervised",),
)

VERDICT_ORDER = (
    verdicts.REPRODUCED,
    verdicts.SMALLER,
    verdicts.LARGER,
    verdicts.CONTRADICTED,
    verdicts.INCONCLUSIVE,
    verdicts.NO_ROOM,
    verdicts.NOT_TESTABLE,
)
BADGE_COLOURS = {  # background, text: dark text on light fills, readable in print too
    verdicts.REPRODUCED: ("#d6f0d6", "#14531a"),
    verdicts.SMALLER: ("#e6f2cf", "#3b5410"),
    verdicts.LARGER: ("#e6f2cf", "#3b5410"),
    verdicts.CONTRADICTED: ("#f7d4d4", "#7a1414"),
    verdicts.INCONCLUSIVE: ("#fbecc7", "#6b4a00"),
    verdicts.NO_ROOM: ("#e4e4e4", "#333333"),
    verdicts.NOT_TESTABLE: ("#e4e4e4", "#333333"),
}
SHORT = {
    verdicts.SMALLER: "reproduced, smaller",
    verdicts.LARGER: "reproduced, larger",
    verdicts.INCONCLUSIVE: "inconclusive",
    verdicts.NO_ROOM: "no room at this budget",
    verdicts.NOT_TESTABLE: "not testable",
}


@dataclass(frozen=True)
class ClaimLine:
    """One claim of the paper: its headline row, every row that tests it, and each row's p
    after Holm's correction within its family (``holm_p``)."""

    headline: Row
    rows: tuple[Row, ...]
    holm: tuple[float, ...]


def counts(rows: list[Row]) -> dict[str, int]:
    """How many rows carry each verdict, in ``VERDICT_ORDER``."""
    found = Counter(r.verdict for r in rows)
    unknown = set(found) - set(VERDICT_ORDER)
    if unknown:
        raise ValueError(f"rows carry verdicts the scorecard does not know: {sorted(unknown)}")
    return {v: found[v] for v in VERDICT_ORDER}


def _claim_of(key: str) -> int:
    """The index in ``CLAIMS`` of the claim whose keys hold ``key``."""
    found = [i for i, keys in enumerate(CLAIMS) if key in keys]
    if not found:
        raise ValueError(f"scorecard row {key!r} belongs to no claim of sgb.scorecard.CLAIMS")
    return found[0]


def claim_lines(rows: list[Row]) -> list[ClaimLine]:
    """The claims that have rows, in ``CLAIMS`` order, each with its headline: the first
    row of its first key (the largest budget) that has rows. Every row belongs to one."""
    grouped: dict[int, list[tuple[Row, float]]] = {}
    for r, corrected in zip(rows, holm_p(rows), strict=True):
        grouped.setdefault(_claim_of(r.key), []).append((r, corrected))
    lines = []
    for i, pairs in sorted(grouped.items()):
        mine = [r for r, _ in pairs]
        headline = next(r for key in CLAIMS[i] for r in mine if r.key == key)
        lines.append(ClaimLine(headline, tuple(mine), tuple(q for _, q in pairs)))
    return lines


def _decimals(width: float) -> int:
    """Decimals that show two significant digits of an interval ``width`` wide."""
    if not math.isfinite(width) or width <= 0:
        return 2
    return max(0, 1 - math.floor(math.log10(width)))


def number_text(x: float, decimals: int) -> str:
    """``x`` at ``decimals``, with thousands separated, a true minus sign; "-" for NaN."""
    if math.isnan(x):
        return "-"
    return f"{x:,.{decimals}f}".replace("-", "\u2212")


def interval_text(estimate: float, low: float, high: float) -> str:
    """``estimate [low, high]``, all three to the precision the interval's width carries."""
    d = _decimals(high - low)
    return f"{number_text(estimate, d)} [{number_text(low, d)}, {number_text(high, d)}]"


def _unit(r: Row) -> str:
    """The unit of row ``r``'s effect (its parenthesised tail), or the effect itself."""
    effect = r.effect
    if effect.endswith(")") and "(" in effect:
        return effect[effect.rindex("(") + 1 : -1]
    return effect


def ours_text(r: Row) -> str:
    """Our estimate of row ``r`` with its interval, or "-" where it has no test."""
    if r.test is None:
        return "-"
    return interval_text(r.test.estimate, r.test.low, r.test.high)


def paper_text(r: Row) -> str:
    """The paper's value of row ``r`` in our unit where the paper gives one, else its words
    (where it states a direction only, the effect that stands in for it is not its value)."""
    if r.paper_effect is None or r.test is None or r.basis:
        return r.paper
    return number_text(r.paper_effect, _decimals(r.test.high - r.test.low))


def badge(verdict: str) -> str:
    """The verdict as a coloured label (HTML)."""
    background, text = BADGE_COLOURS[verdict]
    return (
        f'<span class="sgb-badge" style="background:{background};color:{text};'
        "display:inline-block;max-width:100%;padding:0.1em 0.45em;border-radius:0.8em;"
        f'font-size:0.8em;font-weight:600">{SHORT.get(verdict, verdict)}</span>'
    )


def holm_p(rows: list[Row]) -> list[float]:
    """Each row's p after Holm's correction within its family (``Row.family``; ``nan`` for
    no p)."""
    adjusted = [math.nan] * len(rows)
    for name in dict.fromkeys(r.family for r in rows):
        mine = [i for i, r in enumerate(rows) if r.family == name]
        ps = [math.nan if rows[i].test is None else rows[i].test.p for i in mine]
        for i, q in zip(mine, stats.holm(ps), strict=True):
            adjusted[i] = q
    return adjusted


def holm_text(rows: list[Row]) -> str:
    """Which rows reproduced in direction keep p < 0.05 after Holm's correction within their
    family (markdown)."""
    pairs = list(zip(rows, holm_p(rows), strict=True))
    kept = [(r, q) for r, q in pairs if r.verdict in verdicts.IN_DIRECTION]
    survive = [r for r, q in kept if q < 1 - stats.LEVEL]
    names = "; ".join(f"{r.figure}, {r.setting}" for r in survive) or "none"
    return (
        f"Corrected for the many tests of each figure (Holm, within the figure, theorem or "
        f"chapter), **{len(survive)} of the {len(kept)}** rows reproduced in direction keep "
        f"p < 0.05: {names}. Each row's raw and corrected p are in its details."
    )


def summary_text(rows: list[Row]) -> str:
    """The counts by verdict, in words (markdown)."""
    parts = [f"**{n}** {SHORT.get(v, v)}" for v, n in counts(rows).items()]
    return f"{len(rows)} rows: " + ", ".join(parts)


def _e(text: str) -> str:
    return html_escape.escape(str(text))


def _below(r: Row) -> str:
    """Under a headline's badge: how far below the paper's budget its verdict stands."""
    if not r.below_budget:
        return ""
    return f'<br><small style="color:#555">{_e(r.below_budget)}</small>'


def _detail_table(line: ClaimLine) -> str:
    """Every row of a claim: setting, effect, ours, paper, the effect compared (the paper's
    or its stand-in, with why), test, p, power, budget beside the paper's, verdict and what
    would decide."""
    head = (
        "setting",
        "effect tested",
        "ours (95 % CI)",
        "paper",
        "effect compared",
        "test",
        "p (Holm)",
        "detectable at 80 % power",
        "budget",
        "the paper's budget",
        "verdict",
        "what would decide",
    )
    body = []
    for r, corrected in zip(line.rows, line.holm, strict=True):
        detectable = "-"
        if r.test is not None:
            detectable = number_text(r.test.detectable, _decimals(r.test.high - r.test.low))
        test = "-" if r.test is None else r.test.name
        if r.test is not None and not math.isnan(r.test.dof):
            test += f", dof {r.test.dof:.0f}"
        cells = (
            _e(r.setting),
            _e(r.effect),
            _e(ours_text(r)),
            _e(paper_text(r)),
            _e(r.compared),
            _e(test),
            _e("-" if r.test is None else f"{p_text(r.test.p)} ({p_text(corrected)})"),
            _e(detectable),
            _e(r.budget_text),
            _e(r.paper_budget.text),
            badge(r.verdict),
            _e(r.decide or "-"),
        )
        body.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    header = "".join(f"<th>{h}</th>" for h in head)
    return (
        '<div style="overflow-x:auto"><table class="sgb-detail" style="font-size:0.8em">'
        f"<thead><tr>{header}</tr></thead><tbody>{''.join(body)}</tbody></table></div>"
    )


def html(rows: list[Row]) -> str:
    """The scorecard at a glance: one line per claim (figure, claim, ours, paper, verdict),
    its rows at every setting folded under it."""
    widths = (10, 34, 19, 15, 22)  # per cent of the content width: nothing runs off it
    cols = "".join(f'<col style="width:{w}%">' for w in widths)
    head = "".join(
        f"<th>{h}</th>" for h in ("figure", "claim", "ours (95 % CI)", "paper", "verdict")
    )
    body = []
    for line in claim_lines(rows):
        r = line.headline
        others = Counter(x.verdict for x in line.rows)
        spread = ", ".join(f"{n} {SHORT.get(v, v)}" for v, n in others.items())
        unit = "" if r.test is None else f'<br><small style="color:#555">{_e(_unit(r))}</small>'
        cells = (
            _e(r.figure),
            f'{_e(r.statement)}<br><small style="color:#555">{_e(r.setting)}</small>',
            f"{_e(ours_text(r))}{unit}",
            _e(paper_text(r)),
            badge(r.verdict) + _below(r),
        )
        body.append(
            '<tr class="sgb-claim">' + "".join(f"<td>{c}</td>" for c in cells) + "</tr>"
            '<tr class="sgb-rows"><td colspan="5"><details><summary>'
            f"{len(line.rows)} row{'s' * (len(line.rows) != 1)} at every setting and budget "
            f"({spread})</summary>{_detail_table(line)}</details></td></tr>"
        )
    return (
        '<table class="sgb-scorecard" style="table-layout:fixed;width:100%;'
        f'word-wrap:break-word"><colgroup>{cols}</colgroup><thead><tr>{head}</tr></thead>'
        f"<tbody>{''.join(body)}</tbody></table>"
    )
