"""The paper's claims, each with the verdict its evidence here carries.

``CLAIMS`` is the table of the claims (``Claim``: key, figure, statement, the paper's value,
the effect tested, the effect compared and its basis, the unit that would decide); a row
is ``judge(key, setting, test, budget)``. ``scorecard(results_dir)`` reads the committed
results files and returns one ``Row`` per claim and setting: the paper's value, our
estimate with its 95 % interval, the test, the effect detectable at 80 % power, the budget
behind it and the verdict of
``sgb.verdicts.verdict``. Claims whose results file is missing are left out; claims no run
here can test carry the reason instead of a test.

Effects are signed so that the paper's side is positive where the paper states a
direction. Where the paper gives a direction but no number, the effect used to judge a
contradiction and to size the budget is stated in the row (``Row.basis``).
"""

import functools
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd
from scipy import stats as scipy_stats

from sgb import stats, verdicts
from sgb.reliability import (
    between_sd_at,
    between_sd_bound,
    detectable_between_sd,
    episodes_for,
    episodes_to_detect,
    variance_split,
)
from sgb.results import load as load_results
from sgb.supervised_sweep import figure2_records


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


def _figure3(env: str, infix: str) -> tuple[Claim, Claim]:
    """Figure 3C (Ant) or 3D (HalfCheetah): the level at 128 types and the fall to 16."""
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
            "(Section 2.1's explanation, no number)",
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
            "individuals - clones, P(at least k of N survive)",
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


def judge(
    key: str,
    setting: str,
    test: stats.Test,
    budget: str,
    amount: float | None = None,
    paper_effect: float | None = None,
    basis: str | None = None,
    unit: str | None = None,
) -> Row:
    """The row of the claim ``CLAIMS[key]`` in ``setting``, its verdict the rule's on
    ``test``; an inconclusive one names the sample size (in the claim's unit) at which
    the effect compared becomes detectable. That effect is the claim's, or
    ``paper_effect`` (with its ``basis``) where the setting sets it, and the unit the
    claim's or ``unit``. ``amount``: the budget in the paper's unit for the claim's figure
    (``PAPER_BUDGETS``)."""
    claim = CLAIMS[key]
    effect = claim.paper_effect if paper_effect is None else paper_effect
    if effect is None:
        raise ValueError(f"the claim {key!r} has no effect of its own: pass paper_effect")
    verdict = verdicts.verdict(test, effect)
    decide = ""
    if verdict == verdicts.INCONCLUSIVE:
        decide = f"{verdicts.units_to_decide(test, effect)} {unit or claim.unit}"
    chosen = claim.basis if basis is None else basis
    return Row(claim, setting, effect, chosen, test, budget, verdict, decide, amount)


def untestable(key: str, reason: str) -> Row:
    """The row of a claim no run here can test, and why."""
    return Row(CLAIMS[key], "-", None, "", None, "-", verdicts.NOT_TESTABLE, reason)


# Figure 2 ---------------------------------------------------------------------------------


def _accuracies(
    records: list[dict],
    model: str,
    min_seeds: int = 1,
    score: str = "accuracy",
    count: str = "compression",
) -> dict[float, np.ndarray]:
    """Per setting of ``model`` (keyed by its compression under ``count``: ``"compression"``,
    ours, or ``"compression_authors"``) run at ``min_seeds`` seeds or more, the seeds'
    accuracies (their field ``score``)."""
    by_setting: dict[int, list[dict]] = {}
    for r in records:
        if r["model"] == model:
            by_setting.setdefault(r["setting"], []).append(r)
    return {
        float(np.mean([r[count] for r in rs])): np.array([r[score] for r in rs])
        for rs in by_setting.values()
        if len(rs) >= min_seeds
    }


CPU_EPOCHS, CPU_ROUNDS = 5, 100  # the cpu sweep of Figure 2 (sgb.experiments.fig2)


def figure2_rows(results: dict, dataset: str) -> list[Row]:
    """Figure 2's four statements on ``dataset`` (accuracies in percentage points)."""
    sgb = _accuracies(results["records"], "sgb")
    dgb = _accuracies(results["records"], "dgb")
    low = [min(sgb), min(dgb)]
    ratios_s, ratios_d = sorted(sgb), sorted(dgb)
    seeds = len(sgb[ratios_s[0]])
    budget = f"{seeds} seeds; the cpu sweep (SGB {CPU_EPOCHS} epochs, DGB {CPU_ROUNDS} rounds)"
    setting = f"{dataset}, our DGB layout"
    rows = [
        judge(
            "fig2.dgb_better_low",
            f"{setting}, about {min(low):.0f}x",
            stats.welch(100 * dgb[ratios_d[0]], 100 * sgb[ratios_s[0]]),
            budget,
            amount=CPU_EPOCHS,
        )
    ]
    for i in (-2, -1):
        rows.append(
            judge(
                "fig2.sgb_better_high",
                f"{setting}, about {ratios_s[i]:.0f}x",
                stats.welch(100 * sgb[ratios_s[i]], 100 * dgb[ratios_d[i]]),
                budget,
                amount=CPU_EPOCHS,
            )
        )
    # slow decline: each model's loss from the lowest ratio to the second-highest
    decline_s = 100 * (sgb[ratios_s[0]].mean() - sgb[ratios_s[-2]])
    decline_d = 100 * (dgb[ratios_d[0]].mean() - dgb[ratios_d[-2]])
    rows.append(
        judge(
            "fig2.sgb_declines_slowly",
            f"{setting}, {ratios_s[0]:.0f}x to {ratios_s[-2]:.0f}x",
            stats.welch(decline_d, decline_s),
            budget,
            amount=CPU_EPOCHS,
        )
    )
    return rows


def nearest_pairs(sgb: dict[float, np.ndarray], dgb: dict[float, np.ndarray]) -> list:
    """(SGB ratio, DGB ratio) for every DGB ratio, with the SGB ratio nearest it on a log
    scale (ratios: our convention)."""
    return [(min(sgb, key=lambda r, d=d: abs(math.log(r / d))), d) for d in sorted(dgb) if sgb]


def _welch_table(a: dict, b: dict, pairs: list, names: tuple[str, str]) -> pd.DataFrame:
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


def figure2_ratio_tests(results: dict) -> pd.DataFrame:
    """SGB minus DGB (``_welch_table``) at every ratio the DGB ran, against the SGB at the
    nearest ratio."""
    sgb = _accuracies(results["records"], "sgb")
    dgb = _accuracies(results["records"], "dgb")
    return _welch_table(sgb, dgb, nearest_pairs(sgb, dgb), ("SGB", "DGB"))


def sgb_variant_tests(
    sgb_full: dict, variant: str, baseline: str = "authors", score: str = "accuracy"
) -> pd.DataFrame:
    """How much one change of the SGB's training moves Figure 2: ``variant`` minus
    ``baseline`` (``_welch_table``; variants of ``sgb.experiments.sgb_full``, whose results
    are ``sgb_full``) at every ratio where both have 2 seeds or more, in the individuals'
    accuracy (``score="accuracy"``) or the mean network's (``"mean_network"``)."""
    cells = sgb_full["cells"].values()
    of = {
        name: _accuracies([c for c in cells if c["variant"] == name], "sgb", 2, score)
        for name in (variant, baseline)
    }
    pairs = [(v, b) for b, v in nearest_pairs(of[baseline], of[variant])]
    return _welch_table(of[variant], of[baseline], pairs, (variant, baseline))


FULL_EPOCHS = 50
FULL_BUDGET = f"SGB {FULL_EPOCHS} epochs, 3 draws a minibatch; DGB 500 rounds, best validation"


def figure2_full_rows(sgb_full: dict, dgb_full: dict, rounds: int, dataset: str) -> list[Row]:
    """'The SGB is better at high compression' at the authors' budgets: at every ratio
    where at least 2 seeds of the authors' DGB layout trained all ``rounds``
    (``sgb.experiments.dgb_full``), against each SGB variant of ``sgb.experiments.
    sgb_full`` at the nearest ratio with at least 2 seeds; Welch's t over seeds, in
    accuracy points. ``sgb_full``/``dgb_full``: the results of the two sweeps on ``dataset``
    (its name as the book prints it)."""
    dgb_records = figure2_records(dgb_full, rounds)
    dgb = _accuracies(dgb_records, "dgb", min_seeds=2)
    targets = {  # each ratio's key as _accuracies computes it, to its target ratio
        float(np.mean([c["compression"] for c in dgb_records if c["setting"] == s])): s
        for s in {c["setting"] for c in dgb_records}
    }
    rows = []
    for variant in sgb_full["variants"]:
        records = [c for c in sgb_full["cells"].values() if c["variant"] == variant]
        sgb = _accuracies(records, "sgb", min_seeds=2)
        for ratio_s, ratio_d in nearest_pairs(sgb, dgb):
            test = stats.welch(100 * sgb[ratio_s], 100 * dgb[ratio_d])
            rows.append(
                judge(
                    "fig2.full.sgb_better_high",
                    f"{dataset}, the authors' DGB layout at {ratio_d:.0f}x (target "
                    f"{targets[ratio_d]:g}x), the SGB ({SGB_VARIANTS[variant]}) at {ratio_s:.0f}x",
                    test,
                    f"{test.n} seeds; {FULL_BUDGET}",
                    amount=FULL_EPOCHS,
                )
            )
    return rows


def kl_share_row(sgb_full: dict, dgb_budget: dict, dataset: str) -> Row | None:
    """Section 2.1's explanation of the DGB's lead at low compression, the KL term, at the
    authors' budgets: the SGB with its KL counted once per type pair (a weaker KL, so smaller
    spreads) minus the authors' SGB (per synapse) at the lowest ratio, Welch's t over seeds
    in points, against the DGB's whole lead there (``sgb.experiments.dgb_budget``: one seed,
    500 rounds, the network of best validation accuracy), which the KL would account for.
    ``None`` before both variants have 2 seeds at that ratio."""
    lowest = max(c["setting"] for c in sgb_full["cells"].values())
    of = {
        v: [c for c in sgb_full["cells"].values() if c["variant"] == v and c["setting"] == lowest]
        for v in ("per_pair", "authors")
    }
    if min(len(cells) for cells in of.values()) < 2:
        return None
    per_pair, authors = (np.array([100 * c["accuracy"] for c in of[v]]) for v in of)
    dgb = 100 * dgb_budget["records"][-1]["test_accuracy"]
    lead = dgb - authors.mean()
    ratio = np.mean([c["compression"] for c in of["authors"]])
    return judge(
        "fig2.kl_explains_low",
        f"{dataset} at {ratio:.0f}x: the KL per type pair against per synapse (the authors'); "
        f"the DGB {dgb:.1f} % against the authors' SGB {authors.mean():.1f} %",
        stats.welch(per_pair, authors),
        f"{min(per_pair.size, authors.size)} seeds; SGB {FULL_EPOCHS} epochs; the DGB one "
        f"seed of {dgb_budget['records'][-1]['rounds']} rounds",
        FULL_EPOCHS,
        paper_effect=float(lead),
        basis="the DGB's whole lead over the authors' SGB there, which the KL would account "
        "for; the DGB's one seed gives it no interval",
    )


def supervised_population_rows(sgb_full: dict, dataset: str) -> list[Row]:
    """The abstract's population against its mean network on ``dataset`` (the results of
    ``sgb.experiments.sgb_full``), per KL counting (the authors' per synapse, and per type
    pair) and ratio with 2 seeds or more: the individuals' mean test accuracy minus the mean
    network's, paired by seed, in points."""
    rows = []
    for variant in ("authors", "per_pair"):
        cells = [c for c in sgb_full["cells"].values() if c["variant"] == variant]
        for setting in sorted({c["setting"] for c in cells}, reverse=True):
            seeds = sorted((c for c in cells if c["setting"] == setting), key=lambda c: c["seed"])
            if len(seeds) < 2:
                continue
            ratio = np.mean([c["compression"] for c in seeds])
            test = stats.paired(
                [100 * c["accuracy"] for c in seeds], [100 * c["mean_network"] for c in seeds]
            )
            rows.append(
                judge(
                    "abstract.population_beats_mean_supervised",
                    f"{dataset}, the SGB ({SGB_VARIANTS[variant]}) at {ratio:.0f}x",
                    test,
                    f"{len(seeds)} seeds; SGB {FULL_EPOCHS} epochs, 3 draws a minibatch",
                )
            )
    return rows


SGB_VARIANTS = {
    "authors": "KL per synapse, rho from -7: the authors'",
    "per_pair": "KL per type pair, rho from -7",
    "rho_ours": "KL per synapse, rho from -5",
}


COUNTS = {"compression": "our count", "compression_authors": "the authors' count"}


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


def figure2_crossover(rows: list[Row], results: dict, dataset: str) -> list[Row]:
    """``crossover_row`` of Figure 2's cpu sweep (its ``results``) on ``dataset``, under
    each count of compression (``COUNTS``); its budget that of the sweep's ``rows``."""
    records = results["records"]
    return [
        crossover_row(
            _accuracies(records, "sgb", count=count),
            _accuracies(records, "dgb", count=count),
            f"{dataset}, our DGB layout, {words}",
            "fig2.crossover",
            rows[0].budget,
            rows[0].amount,
        )
        for count, words in COUNTS.items()
    ]


def figure2_full_crossover(sgb_full: dict, dgb_full: dict, rounds: int, dataset: str) -> list[Row]:
    """``crossover_row`` at the authors' budgets (the results of ``sgb.experiments.
    sgb_full`` and ``dgb_full``), for the SGB as the authors train it, over the ratios
    where at least 2 seeds finished, under each count of compression; none before two DGB
    ratios have."""
    cells = [c for c in sgb_full["cells"].values() if c["variant"] == "authors"]
    dgb_records = figure2_records(dgb_full, rounds)
    rows = []
    for count, words in COUNTS.items():
        sgb = _accuracies(cells, "sgb", min_seeds=2, count=count)
        dgb = _accuracies(dgb_records, "dgb", min_seeds=2, count=count)
        if len(dgb) < 2 or len(sgb) < 2:
            return []
        seeds = min(v.size for v in [*sgb.values(), *dgb.values()])
        setting = (
            f"{dataset}, the authors' DGB layout, the SGB ({SGB_VARIANTS['authors']}), {words}"
        )
        budget = f"{seeds} seeds; {FULL_BUDGET}"
        rows.append(crossover_row(sgb, dgb, setting, "fig2.full.crossover", budget, FULL_EPOCHS))
    return rows


# Figure 3 ---------------------------------------------------------------------------------


def _returns(runs: list[dict], settings: str, k: int | None, score: str) -> np.ndarray:
    """The ``score`` of every run at ``settings`` and ``k`` cell types (vanilla: ``None``,
    trained once, under ``"ours"``): ``"final_return"``, the last evaluation, or
    ``"last_two_return"``, the mean of the last two."""
    chosen = [r for r in runs if r["cell_types"] == k and (k is None or r["settings"] == settings)]
    if score == "last_two_return":
        return np.array([np.mean(r["eval_returns"][-2:]) for r in chosen])
    return np.array([r[score] for r in chosen])


FIG3_SETTINGS = {"ours": "our genome", "authors": "the authors' genome"}
REGIME_SETTINGS = {
    "authors": "the authors' genome and regime",
    "authors_aliased": "the authors' genome and regime, their aliased type pairs",
}


def figure3_rows(
    results: dict,
    env: str,
    steps: int,
    score: str = "last_two_return",
    settings_labels: dict[str, str] = FIG3_SETTINGS,
    key_infix: str = "",
) -> list[Row]:
    """Figure 3C/D's level at 128 types and fall near 16, per genome settings named in
    ``settings_labels``, as fractions of the mean vanilla return (each run scored by
    ``score``); keys ``fig3.level_128.{key_infix}{env}`` and ``fig3.fall_16...``."""
    runs = results["runs"]
    vanilla = _returns(runs, "ours", None, score)
    scale = vanilla.mean() if vanilla.size else math.nan
    budget_of = f"{steps / 1e6:g}M steps, seeds: vanilla {vanilla.size}"
    rows = []
    for settings in dict.fromkeys(r["settings"] for r in runs if r["cell_types"] is not None):
        if settings not in settings_labels:
            continue
        top, bottom = _returns(runs, settings, 128, score), _returns(runs, settings, 16, score)
        label = f"{env}, {settings_labels[settings]}"
        budget = f"{budget_of}, 128 types {top.size}, 16 types {bottom.size}"
        if min(top.size, vanilla.size) >= 2:  # the level compares these two arms
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
                )
            )
    return rows


def regime_rows(results: dict, steps: int) -> list[Row]:
    """Figure 3C at the paper's budget (``sgb.experiments.regime``): the level at 128 types
    and the fall to 16 under the authors' regime, each run scored by its last evaluation
    (the authors' window on all 2,048 training environments); per genome (their Gaussian
    per pair, and their aliased pairs). A row appears once the two arms it compares have
    two seeds each."""
    runs = [{**r, "settings": r.get("genome", "authors")} for r in results["runs"]]
    return figure3_rows(
        {"runs": runs}, "ant", steps, "final_return", REGIME_SETTINGS, key_infix="regime."
    )


def typing_rows(results: dict, steps: int, score: str = "last_two_return") -> list[Row]:
    """Chapter 5's explanation of the fall at 16 types under the authors' genome: typing
    the observation entries. Each ablation swaps the input typing alone."""
    runs = results["runs"]
    vanilla = _returns(runs, "ours", None, score).mean()
    pairs = [
        ("authors_untyped_inputs", "authors", "the authors' genome, inputs untyped vs typed"),
        ("ours", "ours_typed_inputs", "our genome, inputs untyped vs typed"),
    ]
    rows = []
    for untyped, typed, label in pairs:
        a, b = _returns(runs, untyped, 16, score), _returns(runs, typed, 16, score)
        if min(a.size, b.size) < 2:
            continue
        rows.append(
            judge(
                "ch5.typing_explains_fall",
                label,
                stats.welch(a / vanilla, b / vanilla),
                f"{steps / 1e6:g}M steps, seeds {a.size} and {b.size}",
            )
        )
    return rows


# Figures 4 and 5 --------------------------------------------------------------------------


def figure4_rows(returns: dict) -> list[Row]:
    """Figure 4E: r between the normal and the long-legged body. The paper's r is compared
    as this measurement would see it: attenuated by the reliability of each body's
    k-episode means (an r of rho between true abilities is observed as about
    rho * sqrt(rel_x rel_y)). Where the individuals cannot be told apart at all (a
    reliability of 0 or below), the budget that decides is in episodes, from the upper
    end of the intraclass correlation's interval."""
    x = np.asarray(returns["normal"]["individuals"])
    y = np.asarray(returns["long_legs"]["individuals"])
    splits = [variance_split(v) for v in (x, y)]
    rel = [max(s.reliability, 0.0) for s in splits]
    attenuation = math.sqrt(rel[0] * rel[1])
    test = stats.fisher_r(x.mean(axis=1), y.mean(axis=1))
    setting = (
        f"ant, 64 types, {x.shape[1]} episodes each (reliabilities "
        f"{splits[0].reliability:.2f}, {splits[1].reliability:.2f})"
    )
    budget = f"{x.shape[0]} individuals x {x.shape[1]} episodes"
    if attenuation > 0:
        return [_legs_row(setting, test, attenuation, budget, "")]
    icc_high = min(s.icc_ci[1] for s in splits)
    episodes = math.ceil(episodes_for(icc_high))
    bound = max(between_sd_bound(s) for s in splits)
    decide = (
        f"individuals that differ: at least {episodes} episodes each (ICC's upper 95 % bound "
        f"{icc_high:.3f}); the SD between individuals is below {bound:.0f}"
    )
    return [_legs_row(setting, test, attenuation, budget, decide)]


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


def variability_row(summary: dict, setting: str, key: str = "title.variability") -> Row | None:
    """The title's claim on one genome: its individuals' innate returns on the normal body
    differ. The effect is the SD between individuals in % of the mean return, its interval
    from the ICC's (``between_sd_at``), its p the one-way F-test's, its detectable effect
    that test's at 80 % power (``detectable_between_sd``); against about 1 % of the return,
    what the authors' plot data imply. Where that cannot be decided, the episodes per
    individual that would. ``None`` for a genome whose mean return is not positive."""
    normal = summary["normal"]
    split, mean = normal["variance_split"], normal["mean_return"]
    if mean <= 0:
        return None
    n, k, within = split["n_individuals"], split["episodes"], split["within_var"]
    percent = 100 / mean
    low, high = (between_sd_at(icc, within) * percent for icc in split["icc_ci"])
    test = stats.Test(
        "one-way F, SD between individuals",
        normal["between_sd"] * percent,
        low,
        high,
        math.nan,
        split["p"],
        detectable_between_sd(n, k, math.sqrt(within)) * percent,
        n,
    )
    row = judge(key, setting, test, f"1 genome x {n} individuals x {k} episodes")
    if row.verdict != verdicts.INCONCLUSIVE:
        return row
    needed = episodes_to_detect(n, math.sqrt(within), row.paper_effect / percent)
    return replace(row, decide=f"{needed} episodes for each of {n} individuals")


def figure5_rows(fig5: dict) -> list[Row]:
    """Figure 5: the population's mean return against its mean network's, our paired
    protocol and the authors' (individuals against the mean network's own sample, Welch).
    The paper's effect: about 1 % of the return (what its plot data imply)."""
    returns = fig5["returns"]["normal"]
    ind, mean_net = np.asarray(returns["individuals"]), np.asarray(returns["mean_network"])
    paired = stats.paired(ind.mean(axis=1), mean_net.mean(axis=1))
    effect = 0.01 * float(mean_net.mean())
    ours = judge(
        "fig5.population_beats_mean",
        f"ant, 64 types, ours: paired, {ind.shape[1]} episodes on shared initial states",
        paired,
        f"{ind.shape[0]} individuals x {ind.shape[1]} episodes",
        paper_effect=effect,
        basis=f"about 1 % of the return ({effect:.0f}), as the authors' plot data imply",
    )
    if ours.verdict == verdicts.INCONCLUSIVE:
        ours = replace(ours, decide=episodes_to_decide(ind - mean_net, effect))
    authors = fig5["authors_protocol"]
    a_all = np.asarray(authors["individuals"])
    a_mean = np.asarray(authors["mean_network"])
    a_effect = 0.01 * float(a_mean.mean())
    theirs = judge(
        "fig5.population_beats_mean",
        f"ant, 64 types, the authors' protocol: sampled actions, {a_all.shape[1]} episodes "
        f"each, mean network {a_mean.size} (Welch; their one-sample t = {authors['t']:.2f})",
        stats.welch(a_all.mean(axis=1), a_mean),
        f"{a_all.shape[0]} individuals x {a_all.shape[1]} episodes, "
        f"{a_mean.size} mean-network episodes",
        paper_effect=a_effect,
        basis=f"about 1 % of the return ({a_effect:.0f})",
    )
    if theirs.verdict == verdicts.INCONCLUSIVE:
        theirs = replace(theirs, decide=episodes_to_decide(a_all, a_effect))
    return [ours, theirs]


def _pooled_test(name: str, pooled: dict, n: int, transform=None) -> stats.Test:
    """A random-effects pooled estimate (DerSimonian-Laird, normal interval) as a ``Test``;
    ``transform`` maps Fisher's z back to r where the pooling was on z."""
    estimate, (low, high) = pooled["random_effects"], pooled["random_effects_ci"]
    se = pooled.get("random_effects_se", pooled.get("random_effects_z_se"))
    z = (math.atanh(estimate) if transform else estimate) / se
    detectable = 2.8 * se if transform is None else transform(2.8 * se)
    p = float(2 * scipy_stats.norm.sf(abs(z)))
    return stats.Test(name, estimate, low, high, math.inf, p, detectable, n)


def populations_rows(results: dict) -> list[Row]:
    """Figures 4E and 5 on several genomes per genome settings (``sgb.experiments.
    populations``), pooled over the genomes by random effects. Figure 4E's r is compared
    with the paper's as this measurement sees it, attenuated by the bodies' mean
    reliabilities."""
    rows = []
    for settings, pooled in results["pooled"].items():
        done = [
            g["summary"]
            for g in results["genomes"].values()
            if g["settings"] == settings and "summary" in g
        ]
        n_genomes = len(done)
        episodes = len(next(iter(results["genomes"].values()))["parts"]["normal"]["returns"][0])
        who = "our" if settings == "ours" else "the authors'"
        budget = f"{n_genomes} genomes x 100 individuals x {episodes} episodes"
        label = f"ant, {who} genome, 64 types, {n_genomes} genomes pooled (random effects)"
        diff = _pooled_test("pooled z", pooled["mean_network_percent"]["fixed_effect"], n_genomes)
        rows.append(
            judge(
                "fig5.population_beats_mean",
                label + ", % of the mean network's return",
                diff,
                budget,
                unit="genomes",
            )
        )
        rels = [
            max(g["normal"]["variance_split"]["reliability"], 0.0)
            * max(g["long_legs"]["variance_split"]["reliability"], 0.0)
            for g in done
        ]
        r = _pooled_test(
            "pooled Fisher z", pooled["legs_r"]["fixed_effect"], 100 * n_genomes, math.tanh
        )
        bound = max(g["normal"].get("between_sd_bound_percent", 0.0) for g in done)
        attenuation = float(np.mean(np.sqrt(rels)))
        rows.append(_legs_row(label, r, attenuation, budget, _sd_below(bound)))
    for genome in results["genomes"].values():
        if "summary" in genome:
            who = "our" if genome["settings"] == "ours" else "the authors'"
            setting = f"ant, {who} genome, 64 types, seed {genome['training_seed']}"
            rows += [r for r in [variability_row(genome["summary"], setting)] if r]
    return rows


def _legs_row(setting: str, r: stats.Test, attenuation: float, budget: str, decide: str) -> Row:
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


def _sd_below(bound: float) -> str:
    """What decides Figure 4E where individuals cannot be told apart: ``bound``, the upper
    bound on their SD in % of the normal body's return."""
    return (
        f"individuals that differ: their SD is below {bound:.1f} % of the return on the normal body"
    )


def _stored_test(stored: dict, scale: float = 1.0) -> stats.Test:
    """A ``stats.Test`` read back from a results file (``null`` dof: a normal test), its
    estimate, interval and detectable effect multiplied by ``scale``."""
    dof = math.inf if stored["dof"] is None else stored["dof"]
    scaled = {k: scale * stored[k] for k in ("estimate", "low", "high", "detectable")}
    return stats.Test(stored["name"], dof=dof, p=stored["p"], n=stored["n"], **scaled)


def regime_population_rows(results: dict) -> list[Row]:
    """Figures 4E and 5 on the genome of the authors' training regime at the paper's budget
    (``reproduce regime_populations``; one genome): Figure 5 under our protocol
    (deterministic actions, the mean network on the same initial states, paired) and under
    theirs (sampled actions), by their one-sample t and by Welch's t, both in % of the mean
    network's return; Figure 4E's r against the paper's as these reliabilities see it."""
    rows = []
    for genome in results["genomes"].values():
        summary = genome.get("summary")
        if summary is None:
            continue
        n, episodes = np.shape(genome["parts"]["normal"]["returns"])
        steps = "5 x 10^7 steps"
        label = f"ant, the authors' regime, {steps}, 64 types, seed {genome['training_seed']}"
        budget = f"1 genome x {n} individuals x {episodes} episodes"
        ours = summary["mean_network"]
        percent = 100 / ours["mean_network_return"]
        tests = [("our protocol (paired, same states)", _stored_test(ours["test"], percent))]
        if "authors_protocol" in summary:
            theirs = summary["authors_protocol"]
            base = 100 / theirs["mean_network_mean"]
            sampled = (
                f"their protocol ({theirs['individual_episodes']} sampled episodes each, "
                f"mean network {theirs['mean_network_episodes']})"
            )
            tests += [
                (f"{sampled}, their one-sample t", _stored_test(theirs["one_sample"], base)),
                (f"{sampled}, Welch t", _stored_test(theirs["welch"], base)),
            ]
        for protocol, test in tests:
            rows.append(
                judge(
                    "fig5.population_beats_mean",
                    f"{label}, {protocol}, % of the mean network's return",
                    test,
                    budget,
                )
            )
        reliabilities = [
            summary[b]["variance_split"]["reliability"] for b in ("normal", "long_legs")
        ]
        attenuation = math.sqrt(max(reliabilities[0], 0.0) * max(reliabilities[1], 0.0))
        bound = summary["normal"].get("between_sd_bound_percent", 0.0)
        legs = _stored_test(summary["legs"]["test"])
        rows.append(_legs_row(label, legs, attenuation, budget, _sd_below(bound)))
        rows += [r for r in [variability_row(summary, label, "title.variability.regime")] if r]
    return rows


# Chapter 6: beyond the paper ---------------------------------------------------------------

HEDGING_Q = "0.5"  # survival: a return of half the mean network's on the normal body
HEDGING_K = "10"  # at least 10 of the 100 members


def evolution_rows(results: dict) -> list[Row]:
    """Evolution without gradients (``sgb.experiments.evolution``): per number of hidden
    types, the stochastic genome's individuals (their mean test accuracy) against the
    deterministic genome's network, paired by seed (both start from the same means)."""
    records = results["records"]
    rows = []
    for k in sorted({r["hidden_types"] for r in records}):
        by_seed = {
            stochastic: {
                r["seed"]: r
                for r in records
                if r["hidden_types"] == k and r["stochastic"] is stochastic
            }
            for stochastic in (True, False)
        }
        seeds = sorted(set(by_seed[True]) & set(by_seed[False]))
        if len(seeds) < 2:
            continue
        stochastic = [100 * np.mean(by_seed[True][s]["individuals"]) for s in seeds]
        deterministic = [100 * by_seed[False][s]["mean_network"] for s in seeds]
        first = by_seed[True][seeds[0]]
        rows.append(
            judge(
                "ch6.evolution_stochastic_helps",
                f"{results['dataset']}, {k} hidden types ({first['compression']:.0f}x)",
                stats.paired(stochastic, deterministic),
                f"{len(first['mean_fitness'])} generations, {len(seeds)} seeds",
            )
        )
    return rows


def bet_hedging_rows(results: dict) -> list[Row]:
    """Bet-hedging (``sgb.experiments.bet_hedging``): per initial spread, the genomes'
    individuals against clones of their mean networks on the four conditions, by
    geometric-mean fitness and by the chance that at least ``HEDGING_K`` of them survive
    (a return of ``HEDGING_Q`` of the mean network's on the normal body); a one-sample t
    over the genomes of their differences."""
    rows = []
    for rho in dict.fromkeys(g["rho_init"] for g in results["genomes"]):
        genomes = [g for g in results["genomes"] if g["rho_init"] == rho]
        if len(genomes) < 2:
            continue
        scores = [g["scores"] for g in genomes]
        sigma = np.mean([g["sigma_trained"] for g in genomes])
        setting = f"rho from {rho:g} (trained sigma {sigma:.2g})"
        n, e = np.shape(genomes[0]["returns"]["individuals"]["normal"])
        budget = f"{len(genomes)} genomes, {n} members x {e} episodes x 4 conditions"
        geometric = [
            s["individuals"]["geometric_fitness"] - s["clones"]["geometric_fitness"] for s in scores
        ]
        rows.append(_across_genomes("ch6.hedging_geometric", setting, geometric, budget))
        survival = [
            s["individuals"]["p_at_least"][HEDGING_Q][HEDGING_K]
            - s["clones"]["p_at_least"][HEDGING_Q][HEDGING_K]
            for s in scores
        ]
        rows.append(_across_genomes("ch6.hedging_survival", setting, survival, budget))
    return rows


def _across_genomes(key: str, setting: str, differences, budget: str) -> Row:
    """A one-sample t over the genomes of individuals - clones; not testable where every
    genome gives the same difference (for a survival chance: both populations always, or
    never, had enough survivors)."""
    if np.ptp(differences) == 0:
        reason = f"every genome gives the same difference, {differences[0]:+.2f}: no spread to test"
        claim = CLAIMS[key]
        return replace(
            untestable(key, reason),
            setting=setting,
            paper_effect=claim.paper_effect,
            basis=claim.basis,
            budget=budget,
        )
    return judge(key, setting, stats.one_sample(differences, 0.0), budget)


def innate_start_rows(results: dict) -> list[Row]:
    """Innate start, then learning on the long-legged Ant (``sgb.experiments.
    innate_start``): per genome and start (mean network, best of 100, random individual),
    the area under its learning curve over the fresh network's of the same seed, less 1;
    a one-sample t over the seeds."""
    runs = results["runs"]
    fresh = {r["seed"]: r["auc"] for r in runs if r["start"] == "fresh"}
    pool = {len(s["individual_means"]) for s in results["selections"]}
    starts = {
        "mean": "its mean network",
        "best": f"the best of {'/'.join(map(str, sorted(pool)))} individuals",
        "random": "a random individual",
    }
    rows = []
    for genome, start in dict.fromkeys((r["genome"], r["start"]) for r in runs):
        group = [r for r in runs if (r["genome"], r["start"]) == (genome, start)]
        gains = [r["auc"] / fresh[r["seed"]] - 1 for r in group if r["seed"] in fresh]
        if start == "fresh" or len(gains) < 2:
            continue
        rows.append(
            judge(
                "ch6.innate_start_rl",
                f"{genome}, from {starts[start]}",
                stats.one_sample(gains, 0.0),
                f"{len(gains)} seeds of {group[0]['eval_steps'][-1] / 1e6:.1f}M steps",
            )
        )
    return rows


def innate_supervised_rows(results: dict) -> list[Row]:
    """The supervised twin (``sgb.experiments.innate_start_supervised``): per start
    (individuals, mean network) and measure, the test accuracy less the fresh networks',
    each a seed's mean over its networks, paired by seed. The measures: over the epoch
    (the area under the accuracy curve over the steps, divided by them) and after it."""
    records = results["records"]
    if len(records) < 2:
        return []

    def score(record: dict, start: str, measure: str) -> float:
        runs = [r for r in record["runs"] if r["start"] == start]
        if measure == "after one epoch":
            return 100 * np.mean([r["accuracy"][-1] for r in runs])
        steps = np.asarray(runs[0]["steps"], dtype=float)
        curve = np.mean([r["accuracy"] for r in runs], axis=0)
        return 100 * float(np.sum(np.diff(steps) * (curve[1:] + curve[:-1]) / 2) / steps[-1])

    rows = []
    for measure in ("over the epoch", "after one epoch"):
        fresh = [score(r, "fresh", measure) for r in records]
        for start in ("individual", "mean"):
            rows.append(
                judge(
                    "ch6.innate_start_supervised",
                    f"{results['dataset']}, from {start}, {measure}",
                    stats.paired([score(r, start, measure) for r in records], fresh),
                    f"{len(records)} seeds, one epoch",
                )
            )
    return rows


# Theorems ---------------------------------------------------------------------------------


def theorem_rows(theory: dict) -> list[Row]:
    """Theorems A.1 and A.3 on the 1-D toys: the sign of the Jensen gap E[L(w)] - L(mu)
    at the start, from its Monte Carlo estimate."""
    rows = []
    for toy, name in (("convex", "A.1"), ("concave", "A.3")):
        t = theory["trajectories"][toy]
        test = stats.estimate_test("Monte Carlo z", t["gap"][0], t["gap_stderr"][0], 1)
        rows.append(
            judge(
                f"theorem.{name}",
                f"1-D {toy} toy",
                test,
                "Monte Carlo draws of the toy (see chapter 3)",
                paper_effect=float(t["prediction"][0]),
            )
        )
    rows += descent_rows(theory)
    if "elbo_toy" in theory:
        rows += sigma_law_rows(theory["elbo_toy"])
    return rows


def descent_rows(theory: dict) -> list[Row]:
    """Theorem A.2's conclusion, that gradient descent drives the Jensen gap below 0, at the
    end of training: on the double well from chapter 3's start, and on each digits
    classifier at its trained spread (its training cross-entropy). The effect compared
    stands in for a number the appendix does not give: the size of the second-order term
    at that point, on the claim's side."""
    toy = theory["trajectories"]["nonconvex"]
    rows = []
    places = [
        (
            f"1-D double well from mu {toy['mu0']:g}, sigma {toy['sigma0']:g}, after "
            f"{len(toy['gap']) - 1} steps",
            toy["gap"][-1],
            toy["gap_stderr"][-1],
            toy["prediction"][-1],
            "Monte Carlo draws of the toy (see chapter 3)",
        )
    ]
    for network in theory["network"]:
        types = network["cell_types"]
        kind = "no types" if all(k is None for k in types) else "/".join(map(str, types)) + " types"
        trained = next(s for s in network["scales"] if s["scale"] == 1.0)
        loss = trained["train_cross_entropy"]
        places.append(
            (
                f"digits classifier, {kind}, at its trained sigma, training cross-entropy",
                loss["gap"],
                loss["stderr"],
                trained["predicted"],
                "the trained classifier's Monte Carlo draws (see chapter 3)",
            )
        )
    for setting, gap, stderr, predicted, budget in places:
        test = stats.estimate_test("Monte Carlo z", gap, stderr, 1)
        basis = "no number given: the size of the second-order term there, on the claim's side"
        rows.append(
            judge("theorem.A.2", setting, test, budget, paper_effect=-abs(predicted), basis=basis)
        )
    return rows


def sigma_law_rows(toy: dict) -> list[Row]:
    """Theorem A.4's sigma step, as the appendix writes it (no entropy term: sigma shrinks to
    0 along positive curvature) against the ELBO the book trains (sigma settles at
    sqrt(c / (H + c lambda))), on the convex toy with the KL on. The effect is where sigma
    settles minus the full ELBO's fixed point; the appendix's step predicts minus that
    fixed point (sigma at 0). The interval is sigma's spread over the last quarter of the
    steps (its stationary SD), a conservative one."""
    rows = []
    runs = toy["runs"]["softplus"]
    for c, predicted, settled, sd in zip(
        toy["kl_weights"],
        toy["predicted_sigma"],
        runs["settled_mean"],
        runs["settled_sd"],
        strict=True,
    ):
        if c <= 0:
            continue
        test = stats.estimate_test("stationary spread", settled - predicted, sd, 1)
        rows.append(
            judge(
                "theorem.A.4",
                f"1-D convex toy, KL weight {c:g}, sigma = softplus(rho)",
                test,
                f"{int(toy['steps'][-1])} gradient steps",
                paper_effect=-float(predicted),
                basis=f"sigma at 0: minus the fixed point with the entropy term ({predicted:.3f})",
            )
        )
    return rows


# The scorecard ----------------------------------------------------------------------------


# results files whose rows are a function of their results alone, in scorecard order
_READ_WHOLE = (  # file, its rows, and the sweep whose genomes it evaluates (if any)
    ("rl/fig5_ant_cpu.json", figure5_rows, "fig3"),
    ("rl/populations_ant_cpu.json", populations_rows, "fig3"),
    ("rl/regime_populations_ant_cpu.json", regime_population_rows, "regime"),
    ("theory_cpu.json", theorem_rows, None),
    ("evolution_digits_cpu.json", evolution_rows, None),
    ("rl/bet_hedging_ant_cpu.json", bet_hedging_rows, None),
    ("rl/innate_start_ant_cpu.json", innate_start_rows, None),
    ("innate_start_supervised_fashion-mnist_cpu.json", innate_supervised_rows, None),
)


def _genomes_at(rows: list[Row], steps: float | None) -> list[Row]:
    """``rows`` of Figures 4 and 5 and of the title's variability, their budget the
    ``steps`` their genomes trained."""
    families = ("Title", "Figure 4", "Figure 5")
    return [replace(r, amount=steps) if r.family in families else r for r in rows]


def scorecard(results_dir: Path) -> list[Row]:
    """Every claim whose results are committed under ``results_dir``, then the claims no
    run here can test. Each file is read through ``sgb.results.load``, which refuses one
    it cannot trust (a ``CorruptFile`` naming it)."""
    load = functools.partial(load_results, results_dir=results_dir, missing_ok=True)
    rows: list[Row] = []
    fig2 = load("fig2_fashion-mnist_cpu.json")
    if fig2 is not None:
        f2 = figure2_rows(fig2["results"], "Fashion-MNIST")
        rows += f2 + figure2_crossover(f2, fig2["results"], "Fashion-MNIST")
    sgb_full = load("sgb_full_fashion-mnist_cpu.json")
    dgb_full = load("dgb_full_fashion-mnist_cpu.json")
    if sgb_full is not None and dgb_full is not None:
        rounds = dgb_full["provenance"]["config"]["dgb"]["rounds"]
        sgb_results, dgb_results = sgb_full["results"], dgb_full["results"]
        full = figure2_full_rows(sgb_results, dgb_results, rounds, "Fashion-MNIST")
        cross = figure2_full_crossover(sgb_results, dgb_results, rounds, "Fashion-MNIST")
        rows += full + cross
        rows += supervised_population_rows(sgb_results, "Fashion-MNIST")
        budget = load("dgb_budget_fashion-mnist_cpu.json")
        share = (
            None
            if budget is None
            else kl_share_row(sgb_results, budget["results"], "Fashion-MNIST")
        )
        rows += [share] if share else []
    genome_steps: dict[str, float] = {}  # sweep -> the steps its genomes trained
    for env in ("ant", "halfcheetah"):
        payload = load(f"rl/fig3_{env}_cpu.json")
        if payload is not None:
            steps = payload["provenance"]["config"]["ppo"]["total_steps"]
            if env == "ant":
                genome_steps["fig3"] = steps
            if _trained(payload["results"]):
                rows += figure3_rows(payload["results"], env, steps)
                if env == "ant":
                    rows += typing_rows(payload["results"], steps)
            else:
                rows.append(untrained_row(env, steps))
    regime = load("rl/regime_ant_cpu.json")
    if regime is not None:
        genome_steps["regime"] = regime["provenance"]["config"]["ppo"]["total_steps"]
        rows += regime_rows(regime["results"], genome_steps["regime"])
    fig4 = load("rl/fig4_ant_cpu.json")
    if fig4 is not None:
        rows += _genomes_at(figure4_rows(fig4["results"]["returns"]), genome_steps.get("fig3"))
    for name, rows_of, sweep in _READ_WHOLE:
        payload = load(name)
        if payload is not None:
            rows += _genomes_at(rows_of(payload["results"]), genome_steps.get(sweep))
    rows += [
        untestable(
            "fig4f.r_terrain",
            "ANYmal on terrain needs Isaac Gym and a GPU; Brax's spring backend has no "
            "height fields (chapter 5 measures two physical niches instead)",
        ),
        untestable(
            "fig2.cifar",
            "CIFAR-10 needs the internet to download; its loader is tested on written files",
        ),
    ]
    return rows


def untrained_row(env: str, steps: int) -> Row:
    """Figure 3 on a body whose vanilla agent learned nothing in ``steps``: no fraction of
    vanilla means anything there."""
    return Row(
        CLAIMS[f"fig3.fall_16.{env}"],
        f"{env}, {steps:,} steps",
        None,
        "",
        None,
        f"{steps:,} steps: vanilla PPO learned nothing",
        verdicts.INCONCLUSIVE,
        "a sweep in which vanilla PPO learns: 2M steps on spring (the cpu profile)",
        steps,
    )


def _trained(results: dict) -> bool:
    """Whether a Figure 3 sweep learned anything: vanilla's mean return above what an
    agent earns standing still or in place (1000 steps x the healthy reward 1 for the
    Ant; 0 for the HalfCheetah)."""
    vanilla = [r["final_return"] for r in results["runs"] if r["cell_types"] is None]
    return len(vanilla) >= 2 and np.mean(vanilla) > (1000 if results["env"] == "ant" else 100)


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
