"""Figures 4 and 5: the individuals of one trained genome (a checkpoint of Figure 3).

- ``fig4``: sample N individuals from a trained SGB and evaluate each for several
  episodes on the Ant with normal and long legs (4E) and on two physical niches (4F);
  Pearson r between conditions.
- ``fig5``: the same individuals against the mean network on the normal Ant, on the same
  initial states; paired t-test.
"""

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from sgb import stats, verdicts
from sgb.claims import Row, episodes_to_decide, genomes_at, judge, legs_row, trained_steps
from sgb.profiles import PROFILE_NAMES
from sgb.prose import GENOMES, NOT_RUN, Card, regime_setting, row_of, row_texts
from sgb.recording import start
from sgb.reliability import between_sd_bound, episodes_for, variance_split
from sgb.results import Records
from sgb.rl.protocols import (
    PopulationConfig,
    authors_protocol,
    compare,
    individuals_vs_mean,
    load_agent,
    population_config,
    population_on,
)
from sgb.rl.runs import checkpoint_root
from sgb.schemas import (
    Correlation,
    Finite,
    List,
    Positive,
    Probability,
    Provenance,
    Record,
    ResultsFile,
    Return,
    Returns,
)


def evaluate_conditions(config: PopulationConfig, results_dir: Path) -> dict:
    """Returns (N, episodes) of the individuals on every condition, and of the mean network
    (on the same initial states) on ``mean_network_conditions``."""
    return population_on(*load_agent(Path(results_dir) / config.checkpoint), config)


def fig4_config(profile: str) -> PopulationConfig:
    """Figure 4: the individuals on every condition; no mean network."""
    return replace(population_config(profile), mean_network_conditions=())


def fig5_config(profile: str) -> PopulationConfig:
    """Figure 5: the individuals and the mean network on the normal Ant."""
    return replace(population_config(profile), conditions=("normal",))


FIG4_PROFILES = {p: fig4_config(p) for p in PROFILE_NAMES}
FIG5_PROFILES = {p: fig5_config(p) for p in PROFILE_NAMES}


def _run_population(profile: str, out_dir: Path, env: str, figure: str) -> Path:
    if env != "ant":
        raise ValueError(
            f"env must be 'ant' for {figure} (the variants are Ant bodies), got {env!r}"
        )
    profiles = FIG4_PROFILES if figure == "fig4" else FIG5_PROFILES
    recording = start(profiles, profile, Path(out_dir) / "rl", f"{figure}_{env}")
    config = recording.config
    agent = load_agent(checkpoint_root(out_dir, config.checkpoint) / config.checkpoint)
    returns = population_on(*agent, config)
    results = {"returns": returns}
    if figure == "fig4":
        results["legs"] = compare(returns, "normal", "long_legs")
        results["niches"] = compare(returns, "slippery", "low_gravity")
    else:
        results["mean_network"] = individuals_vs_mean(returns)
        results["authors_protocol"] = authors_protocol(*agent, config)
    return recording.write(results, [config.seed])


def run_fig4(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Figure 4E/F: individuals on normal vs long legs and on two niches."""
    return _run_population(profile, out_dir, env, "fig4")


def run_fig5(profile: str, out_dir: Path, env: str = "ant") -> Path:
    """Figure 5: individuals against the mean network."""
    return _run_population(profile, out_dir, env, "fig5")


def figure4_rows(returns: "Fig4Returns") -> list[Row]:
    """Figure 4E: r between the normal and the long-legged body. The paper's r is compared
    as this measurement would see it: attenuated by the reliability of each body's
    k-episode means (an r of rho between true abilities is observed as about
    rho * sqrt(rel_x rel_y)). Where the individuals cannot be told apart at all (a
    reliability of 0 or below), the budget that decides is in episodes, from the upper
    end of the intraclass correlation's interval."""
    x = np.asarray(returns.normal.individuals)
    y = np.asarray(returns.long_legs.individuals)
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
        return [legs_row(setting, test, attenuation, budget, "")]
    icc_high = min(s.icc_ci[1] for s in splits)
    episodes = math.ceil(episodes_for(icc_high))
    bound = max(between_sd_bound(s) for s in splits)
    decide = (
        f"individuals that differ: at least {episodes} episodes each (ICC's upper 95 % bound "
        f"{icc_high:.3f}); the SD between individuals is below {bound:.0f}"
    )
    return [legs_row(setting, test, attenuation, budget, decide)]


def figure5_rows(fig5: "Fig5Results") -> list[Row]:
    """Figure 5: the population's mean return against its mean network's, our paired
    protocol and the authors' (individuals against the mean network's own sample, Welch).
    The paper's effect: about 1 % of the return (what its plot data imply)."""
    returns = fig5.returns.normal
    ind, mean_net = np.asarray(returns.individuals), np.asarray(returns.mean_network)
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
    authors = fig5.authors_protocol
    a_all = np.asarray(authors.individuals)
    a_mean = np.asarray(authors.mean_network)
    a_effect = 0.01 * float(a_mean.mean())
    theirs = judge(
        "fig5.population_beats_mean",
        f"ant, 64 types, the authors' protocol: sampled actions, {a_all.shape[1]} episodes "
        f"each, mean network {a_mean.size} (Welch; their one-sample t = {authors.t:.2f})",
        stats.welch(a_all.mean(axis=1), a_mean),
        f"{a_all.shape[0]} individuals x {a_all.shape[1]} episodes, "
        f"{a_mean.size} mean-network episodes",
        paper_effect=a_effect,
        basis=f"about 1 % of the return ({a_effect:.0f})",
    )
    if theirs.verdict == verdicts.INCONCLUSIVE:
        theirs = replace(theirs, decide=episodes_to_decide(a_all, a_effect))
    return [ours, theirs]


def figures4_5(card: Card) -> dict[str, str]:
    """Figure 4E's correlation between bodies (``legs_*``) and Figure 5's individuals
    against the mean network under our protocol and the authors' (``fig5_ours_*``,
    ``fig5_theirs_*``): the first rows of each claim, those of the one genome."""
    fig5 = card.get("fig5.population_beats_mean", []) + [None, None]
    texts = row_texts("legs", row_of(card, "fig4e.r_legs"))
    return texts | row_texts("fig5_ours", fig5[0]) | row_texts("fig5_theirs", fig5[1])


def variability(card: Card) -> dict[str, str]:
    """The title's claim (``title.variability*`` rows): the genomes of the authors' regime
    (``variability_regime``: each row's estimate, interval and verdict) and, per genome settings at
    the cpu sweep's budget, each genome's verdict (``variability_ours``,
    ``variability_authors``); ``NOT_RUN`` where a setting has no row."""
    regime = card.get("title.variability.regime", [])
    shown = "; ".join(f"{regime_setting(r)}: {r.ours} %, **{r.verdict}**" for r in regime)
    texts = {"variability_regime": shown or NOT_RUN}
    for who, settings in GENOMES:
        rows = [r for r in card.get("title.variability", []) if f", {who}, " in r.setting]
        texts[f"variability_{settings}"] = (
            "; ".join(f"{r.setting.split(', ')[-1]}: {r.ours} %, **{r.verdict}**" for r in rows)
            or NOT_RUN
        )
    return texts


def fig4_evidence(records: Records) -> list[Row]:
    """Figure 4's rows, their budget the steps Figure 3's genome trained."""
    payload = records.get("fig4")
    if payload is None:
        return []
    steps = trained_steps(records.get("fig3", "ant"))
    return genomes_at(figure4_rows(payload.results.returns), steps)


def fig5_evidence(records: Records) -> list[Row]:
    """Figure 5's rows, their budget the steps Figure 3's genome trained."""
    payload = records.get("fig5")
    if payload is None:
        return []
    return genomes_at(figure5_rows(payload.results), trained_steps(records.get("fig3", "ant")))


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 5 glues of Figures 4 and 5 and of the title's variability."""
    return figures4_5(card) | variability(card)


def fig45_statistics(fig4: "Fig4", fig5: "Fig5") -> pd.DataFrame:
    """Figures 4E/F and 5 in numbers, one row per test: Pearson r between bodies and
    between niches; our paired t and the authors' one-sample t, with the mean returns of
    the individuals and of the mean network (the centres of their 99 % intervals)."""
    correlations = (
        ("4E", "Pearson r, normal body vs long legs", fig4.results.legs),
        ("4F", "Pearson r, slippery vs low gravity", fig4.results.niches),
    )
    t_tests = (
        ("5", "paired t (our protocol)", fig5.results.mean_network),
        ("5", "one-sample t (the authors' protocol)", fig5.results.authors_protocol),
    )
    rows = [
        {"figure": figure, "test": test, "statistic": r.r, "p": r.p}
        for figure, test, r in correlations
    ] + [
        {
            "figure": figure,
            "test": test,
            "statistic": t.t,
            "p": t.p,
            "individuals' mean return": t.individuals_ci99[0],
            "mean network's return": t.mean_network_ci99[0],
        }
        for figure, test, t in t_tests
    ]
    columns = [
        "figure",
        "test",
        "statistic",
        "p",
        "individuals' mean return",
        "mean network's return",
    ]
    return pd.DataFrame(rows, columns=columns)


class Individuals(Record):
    individuals: Returns


class Fig4Returns(Record):
    normal: Individuals
    long_legs: Individuals
    slippery: Individuals
    low_gravity: Individuals


class CorrelationTest(Record):
    r: Correlation
    p: Probability


class Fig4Results(Record):
    returns: Fig4Returns
    legs: CorrelationTest
    niches: CorrelationTest


class CheckpointConfig(Record):
    checkpoint: str


class Fig4Provenance(Provenance):
    config: CheckpointConfig


class Fig4(ResultsFile):
    provenance: Fig4Provenance
    results: Fig4Results


class Fig5Test(Record):
    """A test of the individuals against the mean network; ci99: mean, low, high."""

    t: Finite
    p: Probability
    dof: Positive
    individuals_ci99: List[Return]
    mean_network_ci99: List[Return]


class AuthorsProtocol(Fig5Test):
    individuals: Returns
    mean_network: List[Return]


class WithMeanNetwork(Individuals):
    mean_network: Returns


class NormalBody(Record):
    normal: WithMeanNetwork


class Fig5Results(Record):
    returns: NormalBody
    mean_network: Fig5Test
    authors_protocol: AuthorsProtocol


class Fig5(ResultsFile):
    results: Fig5Results
