"""The paper's claims, and the rule that makes a test of one a row of the scorecard.

``CLAIMS`` is the table of the claims (``Claim``: key, figure, statement, the paper's value,
the effect tested, the effect compared and its basis, the unit that would decide); a row
is ``judge(key, setting, test, budget)``: the paper's value, our estimate with its 95 %
interval, the test, the effect detectable at 80 % power, the budget behind it and the
verdict of ``sgb.verdicts.verdict``; a claim no run here can test is ``untestable``. Each
experiment judges its own results (its module's ``evidence``), with the row builders
here that several share; ``sgb.gather.scorecard`` gathers them.

Effects are signed so that the paper's side is positive where the paper states a
direction. Where the paper gives a direction but no number, the effect used to judge a
contradiction and to size the budget is stated in the row (``Row.basis``).
"""

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import pandas as pd

from sgb import stats, verdicts
from sgb.reliability import (
    between_sd_at,
    detectable_between_sd,
    episodes_to_detect,
    variance_split,
)
from sgb.schemas import Record, ResultsFile, StoredTest, Training

if TYPE_CHECKING:
    from sgb.supervised_sweep import SweepRecord


class PaperBudget(NamedTuple):
    """The paper's budget for a family's claims: in words, and its amount in the unit in
    which a row states its own (``Row.amount``); ``None`` where the paper ran nothing."""

    text: str
    amount: float | None = None
    unit: str = ""


_FIGURE4 = PaperBudget(
    "a genome of 5 x 10^7 steps; 100 individuals x 10 episodes", 5e7, "the genome's steps"
)
PAPER_BUDGETS = {
    "Figure 2": PaperBudget(
        "5 seeds; SGB 50 epochs (the paper's table), DGB 500 rounds", 50, "SGB epochs"
    ),
    "Figure 3": PaperBudget("5 x 10^7 steps, 5 seeds", 5e7, "steps"),
    "Figure 4": _FIGURE4,
    "Title": _FIGURE4,  # measured on Figure 4E's genome and protocol
    "Figure 5": PaperBudget(
        "a genome of 5 x 10^7 steps; 100 individuals x 10 episodes, the mean network 1024",
        5e7,
        "the genome's steps",
    ),
}
# within this of the paper's amount counts as the paper's budget: the authors' own code runs
# 49,152,000 steps for its 5 x 10^7 (whole updates of 2048 x 5 x 16 steps)
AT_BUDGET = 0.95
NO_PAPER_BUDGET = PaperBudget("none: the paper proves or argues it, and runs nothing")


class Claim(NamedTuple):
    """One statement a row judges: the paper's (or this book's, where the figure names a
    chapter), its fixed parts.

    ``paper_effect`` is the effect the verdict weighs the interval against, signed so that
    the paper's side is positive, in the unit of ``effect``; ``None`` where a setting sets
    it (each row passes its own, ``judge``). ``basis`` says what stands in for the paper's
    number where it gives none ("" where the number is the paper's). ``unit``: what more of
    would decide an inconclusive row (seeds, genomes, ...)."""

    key: str
    figure: str
    statement: str
    paper: str
    effect: str
    paper_effect: float | None
    basis: str
    unit: str

    @property
    def family(self) -> str:
        """Its family for the correction of many tests: its figure without the panel
        letter ("Figure 3C" and "Figure 3D" are "Figure 3"), its theorem, or its chapter."""
        found = re.match(r"Figure \d+", self.figure)
        return found.group(0) if found else self.figure


ONE_POINT = "the paper shows no number: 1 point, the smallest difference taken to matter"
ONE_PERCENT = "about 1 % of the return, as the authors' plot data imply"
_CROSS = "the curves cross: DGB better at low, SGB at high compression"
_CROSS_EFFECT = "compression where the SGB first overtakes the DGB (the count in the setting)"
_FALL = "the return falls off near 16 types (128 against 16 types)"
_VARIABILITY = (
    "individuals of one genome differ in innate return (phenotypic variability)",
    "phenotypic variability (no number)",
    "SD between individuals' innate returns (% of the mean return)",
    1.0,  # % of the return: the SD between individuals the authors' plot data imply
    "about 1 % of the return between individuals, as the authors' plot data imply "
    "(an SD of 10-23 return units)",
    "individuals",
)
_PROPOSED = "(proposed in the Discussion, not measured)"
_JENSEN = "Jensen gap E[L(w)] - L(mu)"


# Figure 3's three claims by name in the chapters' texts: each key is ``{stem}.{infix}{env}``
FIG3_KEYS = {"level": "fig3.level_128", "fall": "fig3.fall_16", "shape": "fig3.shape_32"}


def _figure3(env: str, infix: str) -> tuple[Claim, Claim, Claim]:
    """Figure 3C (Ant) or 3D (HalfCheetah): the level at 128 types, the fall to 16 and its
    shape (gradual to 32 types, quick below)."""
    level = {"ant": 0.75, "halfcheetah": 0.45}[env]
    figure = "Figure 3" + ("C" if env == "ant" else "D")
    return (
        Claim(
            f"fig3.level_128.{infix}{env}",
            figure,
            "at 128 types the SGB falls short of vanilla, to about the paper's fraction",
            f"{level:g} of vanilla",
            "1 - fraction of vanilla at 128 types",
            1 - level,
            f"the paper's shortfall, 1 - {level:g}",
            "seeds",
        ),
        Claim(
            f"fig3.fall_16.{infix}{env}",
            figure,
            _FALL,
            "a quick fall at 16 types",
            "fraction of vanilla, 128 - 16 types",
            0.3,
            "the text gives no number: 0.3 of vanilla, our reading of 'falls off quickly'",
            "seeds",
        ),
        Claim(
            f"fig3.shape_32.{infix}{env}",
            figure,
            "the return declines gradually down to 32 types and falls off quickly below",
            "gradual until the region of 16 types, then a quick fall",
            "fraction of vanilla, (32 - 16 types) - (128 - 32 types)",
            0.2,
            "the text gives no number: the fall's 0.3 of vanilla, 0.25 of it from 32 to 16 "
            "types and 0.05 from 128 to 32",
            "seeds",
        ),
    )


# The claims, in the order of the paper, then this book's: key -> claim.
CLAIMS: dict[str, Claim] = {
    c.key: c
    for c in (
        Claim("title.variability", "Title", *_VARIABILITY),
        Claim("title.variability.regime", "Title", *_VARIABILITY),
        Claim(
            "fig2.dgb_better_low",
            "Figure 2",
            "the DGB is better at low compression",
            "DGB above SGB",
            "DGB - SGB accuracy (points)",
            1.0,
            ONE_POINT,
            "seeds",
        ),
        Claim(
            "fig2.sgb_better_high",
            "Figure 2",
            "the SGB is better at high compression",
            "SGB above DGB",
            "SGB - DGB accuracy (points)",
            1.0,
            ONE_POINT,
            "seeds",
        ),
        Claim(
            "fig2.monotone",
            "Figure 2",
            "performance drops monotonically with increasing compression for both models",
            "every step to a higher compression loses accuracy",
            "the smallest drop between adjacent ratios (points)",
            1.0,
            ONE_POINT,
            "seeds",
        ),
        Claim(
            "fig2.sgb_declines_slowly",
            "Figure 2",
            "the SGB declines more slowly with compression than the DGB",
            "SGB's decline smaller",
            "DGB's decline - SGB's (points)",
            1.0,
            ONE_POINT,
            "seeds",
        ),
        Claim(
            "fig2.crossover",
            "Figure 2",
            _CROSS,
            "a crossover",
            _CROSS_EFFECT,
            None,
            "",
            "seeds",
        ),
        Claim(
            "fig2.full.sgb_better_high",
            "Figure 2",
            "the SGB is better at high compression",
            "SGB above DGB",
            "SGB - DGB accuracy (points)",
            1.0,
            ONE_POINT,
            "seeds",
        ),
        Claim(
            "fig2.full.crossover",
            "Figure 2",
            _CROSS,
            "a crossover",
            _CROSS_EFFECT,
            None,
            "",
            "seeds",
        ),
        Claim(
            "fig2.kl_explains_low",
            "Figure 2",
            "the KL term accounts for the DGB's lead at low compression",
            "(Section 2.2's explanation, no number)",
            "SGB with a weaker KL - the authors' SGB at about 10x (points)",
            None,
            "",
            "seeds",
        ),
        Claim(
            "fig2.cifar",
            "Figure 2D",
            "the same shape on CIFAR-10",
            "crossover on CIFAR-10",
            "-",
            None,
            "",
            "",
        ),
        *_figure3("ant", ""),
        *_figure3("halfcheetah", ""),
        *_figure3("ant", "regime."),
        Claim(
            "ch5.typing_explains_fall",
            "Chapter 5",
            "typing the observation entries causes the fall at 16 types",
            "(the book's explanation, not the paper's)",
            "fraction of vanilla, untyped - typed inputs (16 types)",
            0.3,
            "as large as the fall it would explain: 0.3 of vanilla",
            "seeds",
        ),
        Claim(
            "fig4e.r_legs",
            "Figure 4E",
            "individuals' returns on normal and long legs are positively correlated",
            "r = 0.64",
            "Pearson r",
            None,
            "",
            "individuals",
        ),
        Claim(
            "fig4f.r_terrain",
            "Figure 4F",
            "on rough ground and stairs the individuals' returns are uncorrelated",
            "r = 0.065",
            "Pearson r",
            None,
            "",
            "",
        ),
        Claim(
            "fig5.population_beats_mean",
            "Figure 5",
            "sampled individuals outperform the mean network",
            "t(99) = 12",
            "individuals - mean network (return)",
            1.0,
            ONE_PERCENT,
            "individuals",
        ),
        Claim(
            "abstract.population_beats_mean_supervised",
            "Abstract",
            "a population of individuals outperforms its mean network (supervised)",
            "(the abstract's claim; the paper measures it in Figure 5's Ant only)",
            "individuals - mean network, test accuracy (points)",
            1.0,
            "no number given: 1 point of accuracy",
            "seeds",
        ),
        Claim(
            "abstract.larger_networks",
            "Abstract",
            "stochasticity confers a greater benefit in large networks: at a fixed genome, the "
            "SGB's lead over the DGB grows with the network",
            "(the abstract's and the Discussion's claim, drawn from Figure 2's high compressions)",
            "SGB - DGB test accuracy (points), slope per doubling of the hidden width",
            1.0,
            "no number given: a lead that grows by 1 point each time the network doubles",
            "seeds",
        ),
        Claim(
            "theorem.A.1",
            "Theorem A.1",
            "on a convex loss the population is worse than its mean network (Jensen gap > 0)",
            "gap > 0",
            _JENSEN,
            None,
            "the second-order prediction, sigma^2 L''(mu) / 2",
            "Monte Carlo units",
        ),
        Claim(
            "theorem.A.2",
            "Theorem A.2",
            "gradient descent drives the population below its mean network (Jensen gap < 0)",
            "gap < 0 after descent",
            "Jensen gap E[L(w)] - L(mu) at the end of training",
            None,
            "",
            "Monte Carlo units",
        ),
        Claim(
            "theorem.A.2.saddle",
            "Theorem A.2",
            "the means converge to saddle points of the loss, whose negative curvature makes "
            "the population better than its mean network",
            "saddle points (no number)",
            "negative curvature's share N / (N + P) of the second-order term at the means",
            0.5,
            "no number given: half, where the negative curvature outweighs the positive and "
            "the population beats its mean network to second order",
            "seeds",
        ),
        Claim(
            "theorem.A.3",
            "Theorem A.3",
            "on a concave loss the population is better than its mean network (Jensen gap < 0)",
            "gap < 0",
            _JENSEN,
            None,
            "the second-order prediction, sigma^2 L''(mu) / 2",
            "Monte Carlo units",
        ),
        Claim(
            "theorem.A.4",
            "Theorem A.4",
            "gradient descent shrinks sigma to 0 along positive curvature",
            "sigma -> 0",
            "settled sigma - sqrt(c / (H + c lambda))",
            None,
            "",
            "steps",
        ),
        Claim(
            "ch6.evolution_stochastic_helps",
            "Chapter 6",
            "stochastic development helps a genome that evolution shapes without gradients",
            _PROPOSED,
            "stochastic - deterministic genome, test accuracy (points)",
            1.0,
            "no number given: 1 point of accuracy",
            "seeds",
        ),
        Claim(
            "ch6.hedging_geometric",
            "Chapter 6",
            "variability raises a population's long-run fitness in a changing world",
            "(the abstract's argument, not measured)",
            "individuals - clones, geometric-mean fitness (mean network = 1)",
            0.05,
            "no number given: 5 % of the mean network's fitness at home",
            "genomes",
        ),
        Claim(
            "ch6.hedging_survival",
            "Chapter 6",
            "variability raises the chance that at least some individuals survive",
            "(the abstract's argument, not measured)",
            "individuals - clones, P(at least k of N survive, retested)",
            0.1,
            "no number given: 0.1 of probability",
            "genomes",
        ),
        Claim(
            "ch6.hedging_lineage",
            "Chapter 6",
            "a stochastic genome's individuals survive more often than a deterministic lineage's",
            "(the abstract's argument, not measured)",
            "individuals - a sigma = 0 lineage's members, P(at least 1 of N survives, retested)",
            0.1,
            "no number given: 0.1 of probability",
            "genomes",
        ),
        Claim(
            "ch6.innate_start_rl",
            "Chapter 6",
            "an innate individual is a good start for further learning",
            _PROPOSED,
            "area under the learning curve / the fresh network's, - 1",
            0.1,
            "no number given: 10 % more return over the budget than from scratch",
            "seeds",
        ),
        Claim(
            "ch6.innate_start_supervised",
            "Chapter 6",
            "an innate individual is a good start for further learning",
            _PROPOSED,
            "test accuracy, start - fresh (points)",
            1.0,
            "no number given: 1 point of accuracy",
            "seeds",
        ),
    )
}


@dataclass(frozen=True)
class Row:
    """One claim in one setting, and what the evidence says of it: the test, the effect it
    was weighed against (``paper_effect``, with its ``basis``: the claim's, or the one its
    setting sets) and the verdict."""

    claim: Claim
    setting: str
    paper_effect: float | None
    basis: str
    test: stats.Test | None
    budget: str
    verdict: str
    decide: str
    amount: float | None = None  # our budget in the unit of the paper's (PAPER_BUDGETS)

    @property
    def key(self) -> str:
        return self.claim.key

    @property
    def figure(self) -> str:
        return self.claim.figure

    @property
    def statement(self) -> str:
        return self.claim.statement

    @property
    def paper(self) -> str:
        """The paper's value, in words."""
        return self.claim.paper

    @property
    def effect(self) -> str:
        """What the test estimates."""
        return self.claim.effect

    @property
    def family(self) -> str:
        return self.claim.family

    @property
    def paper_budget(self) -> PaperBudget:
        """The paper's budget for this row's claim."""
        return PAPER_BUDGETS.get(self.family, NO_PAPER_BUDGET)

    @property
    def share(self) -> float | None:
        """Our budget as a fraction of the paper's, in the paper's unit (``None`` where
        either has no amount)."""
        paper = self.paper_budget.amount
        return None if self.amount is None or paper is None else self.amount / paper

    @property
    def below_budget(self) -> str:
        """ "at N % of the paper's budget (unit)" where this row's budget is below the
        paper's, else ""."""
        if self.share is None or self.share >= AT_BUDGET:
            return ""
        return f"at {100 * self.share:.2g} % of the paper's budget ({self.paper_budget.unit})"

    @property
    def budget_text(self) -> str:
        """The row's budget, with how far below the paper's it is where it is."""
        return f"{self.budget} ({self.below_budget})" if self.below_budget else self.budget

    @property
    def compared(self) -> str:
        """The effect the verdict weighs the interval against, with where it comes from:
        the paper's number, or what stands in for it (``basis``, in words)."""
        if self.paper_effect is None:
            return "-"
        basis = self.basis or "the paper's"
        return f"{_num(self.paper_effect)} ({basis})"

    @property
    def ours(self) -> str:
        """Our estimate and its 95 % interval, as text."""
        if self.test is None:
            return "-"
        t = self.test
        return f"{_num(t.estimate)} [{_num(t.low)}, {_num(t.high)}]"


def _num(x: float) -> str:
    """Three significant figures, thousands without a fraction; "-" for no number."""
    if math.isnan(x):
        return "-"
    if abs(x) >= 100:
        return f"{x:.0f}"
    return f"{x:.3g}"


class Room(NamedTuple):
    """The largest effect a setting allows in the paper's direction (``size``, in the
    row's unit) and what bounds it (``bound``, in words)."""

    size: float
    bound: str


def judge(
    key: str,
    setting: str,
    test: stats.Test,
    budget: str,
    amount: float | None = None,
    paper_effect: float | None = None,
    basis: str | None = None,
    unit: str | None = None,
    room: Room | None = None,
) -> Row:
    """The row of the claim ``CLAIMS[key]`` in ``setting``, its verdict the rule's on
    ``test``; an inconclusive one names the sample size (in the claim's unit) at which
    the effect compared becomes detectable, one with too little ``room`` for that effect
    the room and its bound. That effect is the claim's, or ``paper_effect`` (with its
    ``basis``) where the setting sets it, and the unit the claim's or ``unit``.
    ``amount``: the budget in the paper's unit for the claim's figure (``PAPER_BUDGETS``)."""
    claim = CLAIMS[key]
    effect = claim.paper_effect if paper_effect is None else paper_effect
    if effect is None:
        raise ValueError(f"the claim {key!r} has no effect of its own: pass paper_effect")
    verdict = verdicts.verdict(test, effect, room=None if room is None else room.size)
    decide = ""
    if verdict == verdicts.INCONCLUSIVE:
        decide = f"{verdicts.units_to_decide(test, effect)} {unit or claim.unit}"
    elif verdict == verdicts.NO_ROOM:
        decide = (
            f"the largest effect possible here is {room.size:.2f} ({room.bound}), "
            f"below the {abs(effect):g} compared"
        )
    chosen = claim.basis if basis is None else basis
    return Row(claim, setting, effect, chosen, test, budget, verdict, decide, amount)


def untestable(key: str, reason: str) -> Row:
    """The row of a claim no run here can test, and why."""
    return Row(CLAIMS[key], "-", None, "", None, "-", verdicts.NOT_TESTABLE, reason)


# Figure 2 ---------------------------------------------------------------------------------


def accuracies(
    records: "Sequence[SweepRecord]",
    model: str,
    min_seeds: int = 1,
    score: str = "accuracy",
    count: str = "compression",
) -> dict[float, np.ndarray]:
    """Per setting of ``model`` (keyed by its compression under ``count``: ``"compression"``,
    ours, or ``"compression_authors"``) run at ``min_seeds`` seeds or more, the seeds'
    accuracies (their field ``score``: ``"accuracy"`` or ``"mean_network"``)."""
    by_setting: dict[float, list] = {}
    for r in records:
        if r.model == model:
            by_setting.setdefault(r.setting, []).append(r)
    return {
        float(np.mean([getattr(r, count) for r in rs])): np.array([getattr(r, score) for r in rs])
        for rs in by_setting.values()
        if len(rs) >= min_seeds
    }


def nearest_pairs(sgb: dict[float, np.ndarray], dgb: dict[float, np.ndarray]) -> list:
    """(SGB ratio, DGB ratio) for every DGB ratio, with the SGB ratio nearest it on a log
    scale (ratios: our convention)."""
    return [(min(sgb, key=lambda r, d=d: abs(math.log(r / d))), d) for d in sorted(dgb) if sgb]


def welch_table(a: dict, b: dict, pairs: list, names: tuple[str, str]) -> pd.DataFrame:
    """``names[0]`` minus ``names[1]`` accuracy (points) for every (ratio of ``a``, ratio of
    ``b``) in ``pairs`` (ratio -> the seeds' accuracies), with Welch's test: its 95 %
    interval, p, the difference detectable at 80 % power and the seeds of each; indexed by
    ``a``'s ratio (ours, rounded)."""
    columns = [
        "compression (ours)",
        f"{names[0]} - {names[1]} (points)",
        "95 % CI low",
        "95 % CI high",
        "p",
        "detectable at 80 % power",
        f"seeds ({names[0]}, {names[1]})",
    ]
    rows = []
    for ratio_a, ratio_b in pairs:
        test = stats.welch(100 * a[ratio_a], 100 * b[ratio_b])
        seeds = f"{a[ratio_a].size}, {b[ratio_b].size}"
        row = [test.estimate, test.low, test.high, test.p, test.detectable]
        rows.append([round(ratio_a), *row, seeds])
    return pd.DataFrame(rows, columns=columns).set_index(columns[0])


COUNTS = {"compression": "our count", "compression_authors": "the authors' count"}


def monotone_row(
    curve: dict[float, np.ndarray], setting: str, budget: str, amount: float | None
) -> Row | None:
    """ "Performance drops monotonically with compression" on one model's ``curve`` (ratio
    -> the seeds' accuracies, fractions): the weakest step, the pair of adjacent ratios
    whose mean accuracy drops least, its drop in points by Welch's t; monotone where even
    that step's interval lies above 0. None with fewer than 3 ratios (one step is no
    trend)."""
    ratios = sorted(curve)
    if len(ratios) < 3:
        return None
    steps = [
        stats.welch(100 * curve[a], 100 * curve[b])
        for a, b in zip(ratios, ratios[1:], strict=False)
    ]
    i = min(range(len(steps)), key=lambda j: steps[j].estimate)
    where = f"{setting}; weakest of {len(steps)} steps, {ratios[i]:.0f}x to {ratios[i + 1]:.0f}x"
    return judge("fig2.monotone", where, steps[i], budget, amount)


def crossover_row(
    sgb: dict, dgb: dict, setting: str, key: str, budget: str, amount: float | None
) -> Row:
    """The crossover judged from the whole curves of ``sgb`` and ``dgb`` (ratio -> the
    seeds' accuracies): its estimate is the ratio where the SGB's mean curve first
    overtakes the DGB's, its interval that of ``sgb.stats.bootstrap_crossing``, and its
    verdict the share of simulated curves that cross so: reproduced where at least 95 %
    do, contradicted where at most 5 % do, else inconclusive. No test where the mean curves
    do not cross."""
    crossing = stats.bootstrap_crossing(sgb, dgb, rising=True)
    share = crossing.share_crossing
    if share >= stats.LEVEL and not math.isnan(crossing.estimate):
        verdict, decide = verdicts.REPRODUCED, ""
    elif share <= 1 - stats.LEVEL:
        verdict, decide = verdicts.CONTRADICTED, ""
    else:
        verdict = verdicts.INCONCLUSIVE
        decide = f"more seeds: {share:.0%} of simulated curves cross, {stats.LEVEL:.0%} would"
    seeds = min(v.size for v in [*sgb.values(), *dgb.values()])
    test = None  # where the mean curves do not cross: no crossing to put an interval on
    if not math.isnan(crossing.estimate):
        test = stats.Test(
            "t bootstrap of the first crossing",
            crossing.estimate,
            crossing.low,
            crossing.high,
            math.nan,
            math.nan,
            math.nan,
            seeds,
        )
    claim = CLAIMS[key]
    return Row(
        claim,
        f"{setting}; {share:.0%} of simulated curves cross",
        claim.paper_effect,
        claim.basis,
        test,
        budget,
        verdict,
        decide,
        amount,
    )


# Figure 3 ---------------------------------------------------------------------------------


def run_returns(
    runs: Sequence[Training],
    settings: str,
    k: int | None,
    score: str,
    settings_of: Callable[[Training], str] = lambda r: r.settings,
) -> np.ndarray:
    """The ``score`` of every run at ``settings`` (``settings_of`` a run) and ``k`` cell
    types (vanilla: ``None``, trained once, under ``"ours"``): ``"final_return"``, the last
    evaluation, or ``"last_two_return"``, the mean of the last two."""
    chosen = [r for r in runs if r.cell_types == k and (k is None or settings_of(r) == settings)]
    if score == "last_two_return":
        return np.array([np.mean(r.eval_returns[-2:]) for r in chosen])
    return np.array([getattr(r, score) for r in chosen])


FIG3_SETTINGS = {"ours": "our genome", "authors": "the authors' genome"}
REGIME_SETTINGS = {
    "authors": "the authors' genome and regime",
    "authors_aliased": "the authors' genome and regime, their aliased type pairs",
}


# The return of an agent that gains nothing: the HalfCheetah kept in place, the Ant fallen
# over at once (its episode then ends); only walking backwards scores below it.
FLOOR = 0.0


def room_above_floor(returns: np.ndarray, scale: float, who: str) -> Room:
    """How far an arm that should lead (``returns``, its runs' returns) can fall short of
    itself, in ``scale``'s units, before its rival reaches ``FLOOR``: the largest fall or
    gap an agent that goes nowhere would show."""
    return Room(
        float((returns.mean() - FLOOR) / scale),
        f"{who} at {returns.mean():.0f}, the floor at {FLOOR:.0f}: an agent that goes nowhere",
    )


def figure3_setting(
    env: str,
    settings: str,
    settings_labels: Mapping[str, str],
    ablations: Mapping[str, str] | None = None,
) -> str:
    """The setting a Figure 3 row of ``settings`` names (see ``figure3_rows``)."""
    label = f"{env}, {settings_labels[settings]}"
    source = (ablations or {}).get(settings, settings)
    return label if source == settings else f"{label} (128 types: {settings_labels[source]})"


def figure3_rows(
    runs: Sequence[Training],
    env: str,
    steps: int,
    score: str = "last_two_return",
    settings_labels: dict[str, str] = FIG3_SETTINGS,
    key_infix: str = "",
    settings_of: Callable[[Training], str] = lambda r: r.settings,
    on_authors_scale: Callable[[float], float] | None = None,
    ablations: Mapping[str, str] | None = None,
) -> list[Row]:
    """Figure 3C/D's level at 128 types, fall near 16 and the fall's shape (the drop from 32
    to 16 types less the drop from 128 to 32, a contrast of the three arms), per genome
    settings named in ``settings_labels`` (``settings_of`` a run), as fractions of the mean
    vanilla return (each run scored by ``score``); keys ``fig3.level_128.{key_infix}{env}``,
    ``fig3.fall_16...`` and ``fig3.shape_32...``. With ``on_authors_scale`` (a return to
    the authors' Figure 3 scale), the budget says where vanilla stands on it: how far the
    runs have learned. ``ablations``: settings trained at 16 types alone, each mapped to
    the settings whose 128-type runs its fall starts from; they have a fall row only."""
    vanilla = run_returns(runs, "ours", None, score, settings_of)
    scale = vanilla.mean() if vanilla.size else math.nan
    budget_of = f"{steps / 1e6:g}M steps, seeds: vanilla {vanilla.size}"
    if on_authors_scale is not None and vanilla.size:
        budget_of += f" (at {on_authors_scale(scale):.2f} of the authors' scale)"
    rows = []
    for settings in dict.fromkeys(settings_of(r) for r in runs if r.cell_types is not None):
        if settings not in settings_labels:
            continue
        source = (ablations or {}).get(settings, settings)  # whose 128-type runs the fall leaves
        top, bottom = (
            run_returns(runs, source, 128, score, settings_of),
            run_returns(runs, settings, 16, score, settings_of),
        )
        label = figure3_setting(env, settings, settings_labels, ablations)
        budget = f"{budget_of}, 128 types {top.size}, 16 types {bottom.size}"
        if source == settings and min(top.size, vanilla.size) >= 2:  # the level's two arms
            rows.append(
                judge(
                    f"fig3.level_128.{key_infix}{env}",
                    label,
                    stats.welch(vanilla / scale, top / scale),
                    budget,
                    steps,
                )
            )
        if min(top.size, bottom.size) >= 2 and vanilla.size:  # the fall compares these two
            rows.append(
                judge(
                    f"fig3.fall_16.{key_infix}{env}",
                    label,
                    stats.welch(top / scale, bottom / scale),
                    budget,
                    steps,
                    room=room_above_floor(top, scale, "the 128-type agents"),
                )
            )
        middle = run_returns(runs, settings, 32, score, settings_of)
        if source == settings and min(top.size, middle.size, bottom.size) >= 2 and vanilla.size:
            arms = [top / scale, middle / scale, bottom / scale]
            rows.append(
                judge(
                    f"fig3.shape_32.{key_infix}{env}",
                    label,
                    stats.contrast(arms, [-1.0, 2.0, -1.0]),
                    f"{budget}, 32 types {middle.size}",
                    steps,
                )
            )
    return rows


# Figures 4 and 5 --------------------------------------------------------------------------


def episodes_to_decide(per_episode, effect: float) -> str:
    """The evaluation budget at which a population's mean effect of size ``effect`` is
    detectable, from the variance split of ``per_episode`` (N individuals, k episodes):
    the variance of an individual's k-episode mean is sigma_b^2 + sigma_w^2 / k, so more
    episodes help until sigma_b^2 alone sets the standard error."""
    split = variance_split(per_episode)
    n, k = split.n_individuals, split.episodes
    crit = 2.8  # z of 0.975 plus z of 0.8: 80 % power, two-sided 5 %
    allowed = n * (effect / crit) ** 2  # the largest per-individual variance that decides
    if split.between_var >= allowed:
        individuals = math.ceil((crit / effect) ** 2 * (split.between_var + split.within_var / k))
        return f"{individuals} individuals at {k} episodes each (the individuals differ too much)"
    episodes = math.ceil(split.within_var / (allowed - split.between_var))
    return f"{max(episodes, k)} episodes for each of {n} individuals"


def variability_row(normal: Record, setting: str, key: str = "title.variability") -> Row | None:
    """The title's claim on one genome: its individuals' innate returns on the normal body
    differ. The effect is the SD between individuals in % of the mean return, its interval
    from the ICC's (``between_sd_at``), its p the one-way F-test's, its detectable effect
    that test's at 80 % power (``detectable_between_sd``); against about 1 % of the return,
    what the authors' plot data imply. Where that cannot be decided, the episodes per
    individual that would. ``normal``: a genome's summary of the normal body (a
    ``sgb.experiments.populations.PopulationNormal``); ``None`` for a genome whose mean
    return is not positive."""
    split, mean = normal.variance_split, normal.mean_return
    if mean <= 0:
        return None
    n, k, within = split.n_individuals, split.episodes, split.within_var
    percent = 100 / mean
    low, high = (between_sd_at(icc, within) * percent for icc in split.icc_ci)
    test = stats.Test(
        "one-way F, SD between individuals",
        normal.between_sd * percent,
        low,
        high,
        math.nan,
        split.p,
        detectable_between_sd(n, k, math.sqrt(within)) * percent,
        n,
    )
    row = judge(key, setting, test, f"1 genome x {n} individuals x {k} episodes")
    if row.verdict != verdicts.INCONCLUSIVE:
        return row
    needed = episodes_to_detect(n, math.sqrt(within), row.paper_effect / percent)
    return replace(row, decide=f"{needed} episodes for each of {n} individuals")


def legs_row(setting: str, r: stats.Test, attenuation: float, budget: str, decide: str) -> Row:
    """Figure 4E's r against the paper's 0.64 as a measurement of ``attenuation`` (the root
    of the two bodies' reliabilities) sees it; with no reliability, an inconclusive row
    whose ``decide`` says what would tell the individuals apart."""
    if attenuation > 0:
        paper = 0.64 * attenuation
        basis = f"0.64 as seen at these reliabilities: 0.64 x {attenuation:.2f} = {paper:.2f}"
        return judge("fig4e.r_legs", setting, r, budget, paper_effect=paper, basis=basis)
    return Row(
        CLAIMS["fig4e.r_legs"],
        setting,
        0.0,
        "0.64 attenuated by a reliability of 0: nothing observable",
        r,
        budget,
        verdicts.INCONCLUSIVE,
        decide,
    )


def sd_below(bound: float) -> str:
    """What decides Figure 4E where individuals cannot be told apart: ``bound``, the upper
    bound on their SD in % of the normal body's return."""
    return (
        f"individuals that differ: their SD is below {bound:.1f} % of the return on the normal body"
    )


def stored_test(stored: StoredTest, scale: float = 1.0) -> stats.Test:
    """A ``stats.Test`` read back from a results file (``null`` dof: a normal test), its
    estimate, interval and detectable effect multiplied by ``scale``."""
    dof = math.inf if stored.dof is None else stored.dof
    return stats.Test(
        stored.name,
        scale * stored.estimate,
        scale * stored.low,
        scale * stored.high,
        dof,
        stored.p,
        scale * stored.detectable,
        stored.n,
    )


# The scorecard ----------------------------------------------------------------------------


def trained_steps(payload: ResultsFile | None) -> int | None:
    """The environment steps of the PPO runs of a results file (its config's
    ``ppo.total_steps``), or None without the file."""
    return None if payload is None else payload.provenance.config.ppo.total_steps


def genomes_at(rows: list[Row], steps: float | None) -> list[Row]:
    """``rows`` of Figures 4 and 5 and of the title's variability, their budget the
    ``steps`` their genomes trained."""
    families = ("Title", "Figure 4", "Figure 5")
    return [replace(r, amount=steps) if r.family in families else r for r in rows]


def _test_name(test: stats.Test | None) -> str:
    if test is None:
        return "-"
    return test.name if math.isnan(test.dof) else f"{test.name}, dof {test.dof:.0f}"


def table(rows: list[Row]) -> pd.DataFrame:
    """The scorecard as a table: one row per claim and setting."""
    return pd.DataFrame(
        {
            "figure": r.figure,
            "claim": r.statement,
            "setting": r.setting,
            "paper": r.paper,
            "effect tested": r.effect,
            "ours (95 % CI)": r.ours,
            "test": _test_name(r.test),
            "detectable at 80 % power": "-" if r.test is None else _num(r.test.detectable),
            "effect compared": r.compared,
            "budget": r.budget_text,
            "the paper's budget": r.paper_budget.text,
            "verdict": r.verdict,
            "what would decide": r.decide or "-",
        }
        for r in rows
    )


def by_key(rows: list[Row]) -> dict[str, list[Row]]:
    """The rows of each claim key, in scorecard order."""
    out: dict[str, list[Row]] = {}
    for r in rows:
        out.setdefault(r.key, []).append(r)
    return out
