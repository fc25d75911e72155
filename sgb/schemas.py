"""The results files as typed records: one pydantic model per file, the evidence each
experiment's file holds, checked before a reader uses it (``check``), so that a damaged or
edited file is refused with an error naming it and the field, not read into a
``KeyError``, a numpy ``TypeError`` or another verdict.

Every model is strict (a boolean is not a number, a float not an integer), refuses a
non-finite number, bounds what has bounds (a return, an accuracy, a probability) and lets
fields it does not name pass: each names the fields the book's readers use
(``sgb.claims``, ``sgb.prose``, ``sgb.results``, and the returns and accuracies the figures
draw), not every field. A results file writes a non-finite number as null
(``sgb.provenance.NULL_MEANS``); null is accepted only where a field's type says
``| None`` (an SEM of one seed, vanilla's cell types). A field with a default of ``None``
may be absent, but not null. Lists are non-empty unless ``Maybe``-empty, and a table
(``Table``) is rectangular.
"""

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError

from sgb.validation import CorruptFile

REWRITE = "restore it from git, or run its experiment again to write it anew"


class Record(BaseModel):
    """A checked object of a results file: strict, finite, other fields passed through."""

    model_config = ConfigDict(extra="allow", allow_inf_nan=False, strict=True, frozen=True)


# Units and bounds --------------------------------------------------------------------------

EPISODE_STEPS = 1000  # the longest episode of any profile (Brax's episode length)
MAX_SPEED = 50.0  # m/s, far beyond any body here: the fastest committed run earns 13.5 a step
MAX_RETURN = EPISODE_STEPS * MAX_SPEED
"""The largest |return| of an episode: a step earns the body's forward speed (m/s, negative
backwards), plus the Ant's healthy reward of 1, less control and contact costs."""

Finite = float
NonNegative = Annotated[float, Field(ge=0)]
Positive = Annotated[float, Field(gt=0)]
Return = Annotated[float, Field(ge=-MAX_RETURN, le=MAX_RETURN)]
Accuracy = Annotated[float, Field(ge=0, le=1)]  # a fraction of examples, as is evolution's fitness
Probability = Annotated[float, Field(ge=0, le=1)]
Correlation = Annotated[float, Field(ge=-1, le=1)]
Reliability = Annotated[float, Field(le=1)]  # intraclass: negative where individuals do not differ
Compression = Annotated[float, Field(ge=1)]  # the dense network's parameters over the compressed
Speed = Annotated[float, Field(ge=-MAX_SPEED, le=MAX_SPEED)]  # m/s, forward
Seed = Annotated[int, Field(ge=0)]
Count = Annotated[int, Field(ge=1)]
Steps = Annotated[int, Field(ge=0)]
Seconds = NonNegative


class _List:
    """``List[X]``: a non-empty list of X."""

    def __class_getitem__(cls, item: Any) -> Any:
        return Annotated[list[item], Field(min_length=1)]


List = _List
MaybeEmpty = list  # a list that may be empty


def _rectangular(rows: list[list]) -> list[list]:
    for i, row in enumerate(rows):
        if len(row) != len(rows[0]):
            raise ValueError(f"row {i} has {len(row)} entries, the first {len(rows[0])}")
    return rows


class _Table:
    """``Table[X]``: a non-empty rectangular list of non-empty lists of X (rows x columns)."""

    def __class_getitem__(cls, item: Any) -> Any:
        return Annotated[list[List[item]], Field(min_length=1), AfterValidator(_rectangular)]


Table = _Table


def _holding(*keys: str) -> Callable[[dict], dict]:
    def check(value: dict) -> dict:
        missing = [k for k in keys if k not in value]
        if missing:
            raise ValueError(f"no key {missing[0]!r}")
        return value

    return check


def Each(item: Any, *keys: str) -> Any:  # noqa: N802 - reads as a type
    """An object (keys: names of cells, genomes, conditions) whose every value is an
    ``item``, holding at least ``keys``."""
    return Annotated[dict[str, item], AfterValidator(_holding(*keys))]


Returns = Table[Return]  # individuals x episodes


class Provenance(Record):
    config: dict[str, Any]
    profile: str
    seeds: MaybeEmpty[Seed]
    git_commit: str
    git_commits: List[str] = None
    date: str
    wall_time_s: Seconds
    backend: str


class StoredTest(Record):
    """A ``sgb.stats.Test`` as a file stores it; a null dof is a normal test."""

    name: str
    estimate: Finite
    low: Finite
    high: Finite
    dof: Positive | None
    p: Probability
    detectable: NonNegative
    n: Count


class ResultsFile(Record):
    provenance: Provenance


# Chapter 4: Figure 2 -----------------------------------------------------------------------


class Curve(Record):
    """One model's accuracy per setting, over seeds."""

    setting: List[Finite]
    compression: List[Compression]
    mean: List[Accuracy]
    sem: List[NonNegative | None]
    n: List[Count]


class Fig2Summary(Record):
    dense: Curve
    sgb: Curve
    dgb: Curve


class SgbCurve(Record):
    sgb: Curve


class Convention(Record):
    summary: Fig2Summary
    summary_mean_network: SgbCurve
    crossovers: MaybeEmpty[Compression]


class Fig2Record(Record):
    model: str
    setting: Finite
    seed: Seed
    accuracy: Accuracy
    compression: Compression


class Fig2Results(Record):
    records: List[Fig2Record]
    ours: Convention
    authors: Convention


class Fig2(ResultsFile):
    results: Fig2Results


class MeanSigma(Record):
    mean_sigma: NonNegative


class SgbFullCell(Record):
    variant: str
    model: str
    setting: Finite
    seed: Seed
    accuracy: Accuracy
    mean_network: Accuracy
    compression: Compression
    compression_authors: Compression
    layers: List[MeanSigma]


class SgbFullResults(Record):
    cells: Each(SgbFullCell)
    variants: dict[str, Any]


class Sweep(Record):
    ratios: List[Compression]
    seeds: List[Seed]


class SgbFullConfig(Record):
    variants: List[str]
    sweep: Sweep


class SgbFullProvenance(Provenance):
    config: SgbFullConfig


class SgbFull(ResultsFile):
    provenance: SgbFullProvenance
    results: SgbFullResults


class DgbRecord(Record):
    rounds: Count
    best_validation_accuracy: Accuracy
    test_accuracy: Accuracy
    generated_test_accuracy: Accuracy


class DgbFullCell(Record):
    ratio: Compression
    seed: Seed
    gnet_width: Count
    compression_ours: Compression
    compression_authors: Compression
    nominal_ratio: NonNegative
    records: MaybeEmpty[DgbRecord]


class DgbFullResults(Record):
    cells: Each(DgbFullCell)


class Rounds(Record):
    rounds: Count


class DgbFullConfig(Record):
    ratios: List[Compression]
    seeds: List[Seed]
    dgb: Rounds


class DgbFullProvenance(Provenance):
    config: DgbFullConfig


class DgbFull(ResultsFile):
    provenance: DgbFullProvenance
    results: DgbFullResults


class SameBudget(Record):
    epochs: Count
    accuracy: Accuracy


class DgbBudgetResults(Record):
    records: List[DgbRecord]
    uncompressed_same_budget: SameBudget


class DgbBudget(ResultsFile):
    results: DgbBudgetResults


class MeanRho(Record):
    mean_rho: Finite


class GapLayer(Record):
    rho_travel_fraction: Finite
    end: MeanRho


class MeanGapRecord(Record):
    setting: Count
    seed: Seed
    rho_init: Finite
    steps: Count
    layers: List[GapLayer]


class MeanGapSummary(Record):
    """Per setting: the individuals' accuracy and the two networks', each with its SEM."""

    setting: Count
    rho_init: Finite
    moment_recovery: Finite
    sigma_end: NonNegative
    accuracy: Accuracy
    mean_network: Accuracy
    moment_network: Accuracy
    accuracy_sem: NonNegative
    mean_network_sem: NonNegative
    moment_network_sem: NonNegative


class MeanGapResults(Record):
    records: List[MeanGapRecord]
    summary: List[MeanGapSummary]


class MeanGap(ResultsFile):
    results: MeanGapResults


# Chapter 3: the Jensen gap -----------------------------------------------------------------


class Trajectory(Record):
    mu0: Finite
    sigma0: NonNegative
    gap: List[Finite]
    gap_stderr: List[NonNegative]
    prediction: List[Finite]


class Trajectories(Record):
    convex: Trajectory
    concave: Trajectory
    nonconvex: Trajectory


class Settled(Record):
    settled_mean: List[NonNegative]
    settled_sd: List[NonNegative]


class SigmaRuns(Record):
    softplus: Settled


class ElboToy(Record):
    kl_weights: List[NonNegative]
    predicted_sigma: List[NonNegative]
    steps: List[Steps]
    runs: SigmaRuns


class Gap(Record):
    gap: Finite
    stderr: NonNegative


class ScaleGap(Record):
    scale: NonNegative
    predicted: Finite
    train_cross_entropy: Gap
    train_error_rate: Gap
    test_error_rate: Gap


class LayerGap(Gap):
    layer: str
    predicted: Finite


class MeanNetworkAccuracy(Record):
    mean_network: Accuracy


class Hutchinson(Record):
    value: Finite
    stderr: NonNegative


class NetworkGap(Record):
    cell_types: List[Count | None]
    sigma_mean: NonNegative
    accuracy: MeanNetworkAccuracy
    hutchinson_probes: Count
    hutchinson: Hutchinson
    scales: List[ScaleGap]
    layers: List[LayerGap]


class Fit(Record):
    median_ratio: Finite
    ratio_q10: Finite
    ratio_q90: Finite
    log_correlation: Correlation


class Fits(Record):
    at_mean: Fit
    population: Fit


class BothAccuracies(MeanNetworkAccuracy):
    population_average: Accuracy


class Sigma2(Record):
    sigma2: List[NonNegative]


class FixedPointRun(Record):
    epochs: Count
    kl_weight: NonNegative
    prior_sigma: Positive
    population_hessians: Count
    accuracy: BothAccuracies
    layers: Each(Sigma2)
    summary: Fits


class FixedPoint(Record):
    cell_types: List[Count | None]
    runs: List[FixedPointRun]


class TheoryResults(Record):
    trajectories: Trajectories
    elbo_toy: ElboToy = None
    network: List[NetworkGap]
    fixed_point: List[FixedPoint] = None


class Theory(ResultsFile):
    results: TheoryResults


# Chapter 5: Brax -------------------------------------------------------------------------


class Fig3Summary(Record):
    settings: str
    cell_types: Count | None
    mean_return: Return
    sem_return: NonNegative | None
    fraction: Finite | None
    sem_fraction: NonNegative | None
    n_seeds: Count


class Training(Record):
    """One PPO run: its evaluations and its score."""

    cell_types: Count | None
    seed: Seed
    final_return: Return
    last_two_return: Return
    eval_steps: List[Steps]
    eval_returns: List[Return]


class Fig3Run(Training):
    settings: str


class Fig3Results(Record):
    env: str
    runs: List[Fig3Run]
    summary: List[Fig3Summary]
    summary_last_two: List[Fig3Summary] = None


class TotalSteps(Record):
    total_steps: Count


class PpoConfig(Record):
    ppo: TotalSteps


class PpoProvenance(Provenance):
    config: PpoConfig


class Fig3(ResultsFile):
    provenance: PpoProvenance
    results: Fig3Results


class RegimeRun(Training):
    authors_scale: Finite
    train_steps_per_s: Positive
    wall_time_s: Seconds


class RegimeResults(Record):
    env: str
    runs: List[RegimeRun]


class Regime(ResultsFile):
    results: RegimeResults


class PeerRun(Training):
    label: str


class PeerComparison(Record):
    """One evaluation point: our seeds' returns beside the authors' one run."""

    label: str
    step: Steps
    ours: List[Return]
    mean: Return
    sd: NonNegative | None
    theirs: Return | None
    interval: List[Finite] | None
    inside: bool | None


class RegimePeerResults(Record):
    env: str
    runs: MaybeEmpty[PeerRun]
    comparison: MaybeEmpty[PeerComparison]


class RegimePeer(ResultsFile):
    results: RegimePeerResults


class GaitRun(Record):
    cell_types: Count | None
    seed: Seed
    genome: str
    window_return: Return
    forward_velocity: Speed
    forward_velocity_sem: Annotated[float, Field(ge=0, le=MAX_SPEED)]
    walks: bool


class RegimeGaitResults(Record):
    walking_speed: Positive
    runs: MaybeEmpty[GaitRun]


class RegimeGait(ResultsFile):
    results: RegimeGaitResults


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


class VarianceSplit(Record):
    reliability: Reliability
    icc: Reliability


class Split(Record):
    variance_split: VarianceSplit


class NormalSplit(Split):
    between_sd_bound_percent: NonNegative = None


class PopulationNormal(NormalSplit):
    mean_return: Return


class MeanNetworkPercent(Record):
    percent: Finite
    percent_ci: List[Finite]


class PopulationSummary(Record):
    normal: PopulationNormal
    long_legs: Split
    mean_network: MeanNetworkPercent


class ReturnsPart(Record):
    returns: Returns


class NormalPart(Record):
    normal: ReturnsPart


class PopulationGenome(Record):
    settings: str
    parts: NormalPart
    summary: PopulationSummary = None


class Pooled(Record):
    random_effects: Finite
    random_effects_ci: List[Finite]
    random_effects_se: Positive


class PooledR(Record):
    """Pooled on Fisher's z."""

    random_effects: Correlation
    random_effects_ci: List[Correlation]
    random_effects_z_se: Positive


class FixedEffect(Record):
    fixed_effect: Pooled


class FixedEffectR(Record):
    fixed_effect: PooledR


class PooledSetting(Record):
    mean_network_percent: FixedEffect
    legs_r: FixedEffectR


class PopulationsResults(Record):
    genomes: Each(PopulationGenome)
    pooled: Each(PooledSetting)


class Populations(ResultsFile):
    results: PopulationsResults


class OurProtocol(Record):
    mean_network_return: Return
    test: StoredTest


class TheirProtocol(Record):
    individual_episodes: Count
    mean_network_episodes: Count
    mean_network_mean: Return
    one_sample: StoredTest
    welch: StoredTest


class SplitHalf(Record):
    episodes: Count
    r: Correlation
    r_ci: List[Correlation]


class RegimeNormal(NormalSplit):
    split_half: SplitHalf


class LegsTest(Record):
    test: StoredTest


class RegimePopulationSummary(Record):
    mean_network: OurProtocol
    authors_protocol: TheirProtocol = None
    normal: RegimeNormal
    long_legs: Split
    legs: LegsTest


class RegimePopulationGenome(Record):
    training_seed: Seed
    parts: NormalPart
    summary: RegimePopulationSummary = None


class RegimePopulationsResults(Record):
    genomes: Each(RegimePopulationGenome)


class RegimePopulations(ResultsFile):
    results: RegimePopulationsResults


class PairedTest(Record):
    t: Finite
    p: Probability


class SpreadRun(Record):
    rho_init: Finite
    sigma_init: Positive
    seed: Seed
    checkpoint: str
    sigma_trained: NonNegative
    individuals_mean: Return
    individuals_sd: NonNegative
    mean_network_mean: Return
    paired_test: PairedTest


class SpreadResults(Record):
    runs: List[SpreadRun]


class Spread(ResultsFile):
    results: SpreadResults


class Speeds(Record):
    train_steps_per_s: Positive
    wall_time_s: Seconds


class Reach(Speeds):
    eval_steps: List[Steps]
    eval_returns: List[Return]


class BenchBackendsResults(Record):
    throughput: Each(Speeds, "spring", "mjx")
    reach: Reach


class BenchBackends(ResultsFile):
    results: BenchBackendsResults


class BenchRun(Speeds):
    seed: Seed
    final_return: Return
    eval_returns: List[Return]


class Throughput(Record):
    population_steps_per_s: Positive
    bare_env_steps_per_s: Positive
    ratio: Positive


class TrainingThroughput(Record):
    steps_per_s: Each(Positive)


class BenchRlResults(Record):
    throughput: Throughput
    training_throughput: TrainingThroughput
    ours: List[BenchRun]
    brax: List[BenchRun]
    sgb_64_types: List[BenchRun]


class BenchRl(ResultsFile):
    results: BenchRlResults


class BenchRegimeRow(Record):
    """One configuration (vanilla: null cell types), each phase's speed."""

    cell_types: Count | None
    env_steps_per_s: Each(Positive)
    ratio_to_simulator: Each(Positive)
    seconds: Each(List[Positive])
    bound_env_steps_per_s: Positive
    iteration_over_bound: Positive
    bound_over_simulator: Positive
    sgd_flops_per_env_step: Positive
    update_gflops: Positive
    matmul_gflops: Positive
    run_hours: Each(Positive)


class BenchRegimeResults(Record):
    rows: List[BenchRegimeRow]
    table: List[str]


class BenchRegime(ResultsFile):
    results: BenchRegimeResults


class Workload(Record):
    """One workload: its speed alone and two at once."""

    alone: List[Positive]
    two_at_once: List[Positive]
    ratios: List[Positive]
    median_ratio: Positive


class BenchParallel(ResultsFile):
    results: Each(Workload)


# Chapter 6: beyond the paper ---------------------------------------------------------------


class EvolutionRecord(Record):
    hidden_types: Count
    stochastic: bool
    seed: Seed
    compression: Compression
    mean_fitness: List[Accuracy]
    individuals: List[Accuracy]
    mean_network: Accuracy
    sigma_mean: NonNegative
    wall_time_s: Seconds


class EvolutionResults(Record):
    dataset: str
    records: List[EvolutionRecord]


class Candidates(Record):
    candidates: Count


class EvolutionConfig(Record):
    base: Candidates


class EvolutionProvenance(Provenance):
    config: EvolutionConfig


class Evolution(ResultsFile):
    provenance: EvolutionProvenance
    results: EvolutionResults


class HedgingScore(Record):
    """The survival the scorecard reads: threshold 0.5, at least 10 members."""

    geometric_fitness: Finite
    mean_fitness: Finite
    p_at_least: Each(Each(Probability, "10"), "0.5")


class HedgingReturns(Record):
    individuals: Each(Returns, "normal")
    clones: Each(Returns, "normal")


class HedgingScores(Record):
    individuals: HedgingScore
    clones: HedgingScore


class HedgingGenome(Record):
    rho_init: Finite
    training_seed: Seed
    sigma_trained: NonNegative
    scale: Return
    returns: HedgingReturns
    scores: HedgingScores


class BetHedgingResults(Record):
    genomes: List[HedgingGenome]


class BetHedging(ResultsFile):
    results: BetHedgingResults


class Selection(Record):
    individual_means: List[Return]


class InnateRun(Record):
    genome: str | None
    start: str
    seed: Seed
    auc: Return
    eval_steps: List[Steps]
    eval_returns: List[Return]


class InnateStartResults(Record):
    complete: bool
    selections: List[Selection]
    runs: List[InnateRun]
    summary: List[dict[str, Any]]


class InnateStart(ResultsFile):
    results: InnateStartResults


class CurveOverSteps(Record):
    start: str
    steps: List[Steps]
    accuracy: List[Accuracy]


class CurveRuns(Record):
    runs: List[CurveOverSteps]


class CurveSummary(CurveOverSteps):
    accuracy_sem: List[NonNegative | None]
    n_seeds: Count


class InnateStartSupervisedResults(Record):
    dataset: str
    records: MaybeEmpty[CurveRuns]
    summary: List[CurveSummary]


class InnateStartSupervised(ResultsFile):
    results: InnateStartSupervisedResults


# Which model a file is under, by its path under the results directory: ``*`` stands for
# a dataset, an environment or a profile (lower case, digits and hyphens).
SCHEMAS: dict[str, type[ResultsFile]] = {
    "fig2_*_*.json": Fig2,
    "sgb_full_*_*.json": SgbFull,
    "dgb_full_*_*.json": DgbFull,
    "dgb_budget_*_*.json": DgbBudget,
    "mean_gap_*_*.json": MeanGap,
    "theory_*.json": Theory,
    "evolution_*_*.json": Evolution,
    "innate_start_supervised_*_*.json": InnateStartSupervised,
    "bench_parallel.json": BenchParallel,
    "rl/fig3_*_*.json": Fig3,
    "rl/fig4_*_*.json": Fig4,
    "rl/fig5_*_*.json": Fig5,
    "rl/regime_*_*.json": Regime,
    "rl/populations_*_*.json": Populations,
    "rl/regime_populations_*_*.json": RegimePopulations,
    "rl/regime_gait_*_*.json": RegimeGait,
    "rl/regime_peer_*_*.json": RegimePeer,
    "rl/spread_*_*.json": Spread,
    "rl/bet_hedging_*_*.json": BetHedging,
    "rl/innate_start_*_*.json": InnateStart,
    "rl/bench_backends.json": BenchBackends,
    "rl/bench_rl.json": BenchRl,
    "rl/bench_regime.json": BenchRegime,
}


def schema_of(name: str) -> type[ResultsFile]:
    """The model of results file ``name`` (its path under the results directory, e.g.
    ``"rl/fig5_ant_cpu.json"``); a ValueError for a name that no pattern of ``SCHEMAS``, or
    more than one, covers."""
    found = [
        model
        for pattern, model in SCHEMAS.items()
        if re.fullmatch(re.escape(pattern).replace(r"\*", "[a-z0-9-]+"), name)
    ]
    if len(found) != 1:
        raise ValueError(f"{len(found) or 'no'} schemas in sgb.schemas cover results file {name}")
    return found[0]


def _where(loc: tuple) -> str:
    """A field's place as a reader writes it: ``results.runs[3].final_return``."""
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _shown(value: Any) -> str:
    text = json.dumps(value, default=str)
    return text if len(text) <= 40 else text[:37] + "..."


def check(name: str, payload: Any, path: str | Path) -> None:
    """Refuse ``payload``, the contents of results file ``name`` read from ``path``, unless
    its model accepts it: a ``CorruptFile`` naming the file and the first field that is
    missing, null where a number is read, or outside its bounds."""
    try:
        schema_of(name).model_validate(payload)
    except ValidationError as error:
        first = error.errors(include_url=False)[0]
        where = _where(first["loc"])
        if first["type"] == "missing":
            problem = f"no {where}"
        elif first["type"] == "value_error":  # a table's shape, an object's keys
            problem = f"{where}: {first['ctx']['error']}"
        else:
            problem = f"{where} = {_shown(first['input'])}: {first['msg']}"
        raise CorruptFile(path, f"has {problem}", REWRITE, "results file") from None
