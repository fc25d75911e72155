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


class TotalSteps(Record):
    total_steps: Count


class PpoConfig(Record):
    ppo: TotalSteps


class PpoProvenance(Provenance):
    """The provenance of a file of PPO runs: its config's ``ppo.total_steps``."""

    config: PpoConfig


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


class DgbRecord(Record):
    rounds: Count
    best_validation_accuracy: Accuracy
    test_accuracy: Accuracy
    generated_test_accuracy: Accuracy


# Chapter 3: the Jensen gap -----------------------------------------------------------------


# Chapter 5: Brax -------------------------------------------------------------------------


class Training(Record):
    """One PPO run: its evaluations and its score."""

    cell_types: Count | None
    seed: Seed
    final_return: Return
    last_two_return: Return
    eval_steps: List[Steps]
    eval_returns: List[Return]


class Speeds(Record):
    train_steps_per_s: Positive
    wall_time_s: Seconds


class Reach(Speeds):
    backend: str
    eval_steps: List[Steps]
    eval_returns: List[Return]


class BenchBackendsResults(Record):
    env: str
    throughput_steps: Count
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
    evaluation_share: Probability  # a run's evaluations, of its training and evaluations
    update_shares: Each(Finite)  # forward, backward, optimiser


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


def _where(loc: tuple) -> str:
    """A field's place as a reader writes it: ``results.runs[3].final_return``."""
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _shown(value: Any) -> str:
    text = json.dumps(value, default=str)
    return text if len(text) <= 40 else text[:37] + "..."


def check(model: type[ResultsFile], payload: Any, path: str | Path) -> ResultsFile:
    """``payload``, the contents of the results file at ``path``, as a record of ``model``;
    a ``CorruptFile`` naming the file and the first field that is missing, null where a
    number is read, or outside its bounds, where the model refuses it."""
    try:
        return model.model_validate(payload)
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
