"""Chapter 6, the supervised twin of ``innate_start`` (registered as
``innate_start_supervised``): SGB individuals, their mean network and fresh networks, each
fine-tuned as a plain MLP.

Per seed, one SGB is trained as Figure 2's sweep trains its cell nearest ``ratio``
(``sgb.supervised_sweep.cell_config``: the sweep's config, KL per synapse, from its
rho start), on Fashion-MNIST at ``cpu``. Its K = ``eval_individuals`` individuals (the
ones ``sgb.supervised.train_and_evaluate`` scores, drawn with the same keys), its mean
network and K freshly initialised networks of the same widths then become plain
``sgb.classifiers.DenseClassifier`` networks (``plain_params``: each individual's drawn
kernels, or the type means expanded, and the SGB's biases) and train for one epoch with
Adam on cross-entropy, at the sweep's uncompressed-network settings (learning rate and
batch size of its ``dense`` config), every network of a seed on the same minibatches.
The test accuracy is recorded before, at ``evaluations`` evenly spaced points within the
epoch, and at its end.

``run`` writes ``innate_start_supervised_<dataset>_<profile>.json`` after every seed (one
record each: the SGB's innate accuracies and every fine-tuning curve), atomically; a rerun
skips the seeds it holds.

Cost (``cpu``), measured per CPU-second on one core with one XLA thread: an epoch of the
SGB at 10x (785 hidden types of 800) took about 11 CPU-seconds, so its 5 epochs about 55;
one fine-tuning epoch (600 steps of 100 examples and 5 test evaluations) 2.6, so the 21 of
a seed (10 individuals, the mean network, 10 fresh) about 55: about 2 minutes a seed, 6
for the 3 seeds, with compiling and loading the data. The ``smoke`` run (digits) took 16
CPU-seconds.
"""

import dataclasses
import math
import time
from pathlib import Path
from typing import Any

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd

from sgb import stats, validation
from sgb.cells import train_cells
from sgb.claims import Row, judge
from sgb.classifiers import DenseClassifier, dense_sizes
from sgb.compression import compression, setting_for_ratio
from sgb.data import Dataset, load
from sgb.individuals import individual_kernels
from sgb.prose import mean_sem
from sgb.provenance import git_commit
from sgb.recording import Recording, start
from sgb.results import Records
from sgb.schemas import Accuracy, Count, List, MaybeEmpty, NonNegative, Record, ResultsFile, Steps
from sgb.stats import sem
from sgb.supervised import dense_accuracy, train_and_evaluate
from sgb.supervised_sweep import SWEEPS, CompressionSweep, cell_config
from sgb.training import adam_state, cross_entropy_step, train_loop

STARTS = ("individual", "mean", "fresh")
INNATE_KEY = 10_000  # train_and_evaluate draws its individuals from key(seed + this)
FRESH_KEY = 20_000  # the fresh networks' initial keys: split(key(seed + this), K)
_STEP = jax.jit(cross_entropy_step, donate_argnums=0)  # steps update the state in place


@dataclasses.dataclass(frozen=True)
class SupervisedStartConfig:
    """The SGB of Figure 2's ``sweep`` nearest ``ratio`` (our convention) on ``dataset``,
    one for each of ``seeds``, and ``evaluations`` test evaluations within the epoch of
    fine-tuning."""

    dataset: str = "fashion-mnist"
    sweep: CompressionSweep = SWEEPS["cpu"]["fashion-mnist"]["sweep"]
    ratio: float = 10.0
    seeds: tuple[int, ...] = (0, 1, 2)
    evaluations: int = 4

    def __post_init__(self) -> None:
        validation.instance("sweep", self.sweep, CompressionSweep)
        if self.sweep.conv_features:
            raise ValueError("the fine-tuned networks are MLPs: the sweep has no conv trunk")
        validation.positive("ratio", self.ratio)
        validation.integers("seeds", self.seeds, minimum=0)
        validation.integer("evaluations", self.evaluations)


def plain_params(model: nn.Module, params: Any, x: np.ndarray, key: jax.Array | None) -> dict:
    """The ``{"params": ...}`` of the ``DenseClassifier`` of the SGB MLP ``model``'s widths
    whose kernels (n_in, n_out) are those of the individual drawn with ``key`` (``None``:
    the mean network) and whose biases (n_out,) are the SGB's; ``x``: inputs like the
    model's (one example is enough)."""
    kernels = individual_kernels(model, params, x, key)
    return {
        "params": {
            f"dense_{i}": {"kernel": kernel, "bias": params["params"][path]["bias"]}
            for i, (path, kernel) in enumerate(kernels.items())
        }
    }


def fine_tune(
    model: DenseClassifier,
    params: Any,
    data: Dataset,
    sweep: CompressionSweep,
    evaluations: int,
    seed: int,
) -> dict[str, Any]:
    """One epoch of Adam on cross-entropy from ``params`` (the sweep's dense learning rate
    and batch size; minibatch order from ``seed``): ``steps`` and test ``accuracy`` at step
    0, every ``n_batches // evaluations`` steps and at the end, and the epoch's loss."""
    dense = sweep.dense
    n_batches = max(1, len(data.x_train) // dense.batch_size)
    curve: dict[str, list] = {"steps": [], "accuracy": []}

    def record(state: Any) -> Any:
        curve["steps"].append(int(state.step))
        curve["accuracy"].append(dense_accuracy(model, state.params, data.x_test, data.y_test))
        return state

    own = jax.tree_util.tree_map(jnp.copy, params)  # own buffers: the steps donate them
    state = record(adam_state(model.apply, own, dense.learning_rate))
    state, history = train_loop(
        state,
        _STEP,
        data.x_train,
        data.y_train,
        batch_size=dense.batch_size,
        num_steps=n_batches,
        seed=seed,
        hook=record,
        hook_every=max(1, n_batches // evaluations),
        progress=False,
        num_classes=data.num_classes,
    )
    if curve["steps"][-1] != n_batches:
        record(state)
    return {**curve, "final_loss": history[-1]["loss"]}


def run_seed(config: SupervisedStartConfig, data: Dataset, seed: int) -> dict[str, Any]:
    """Train the seed's SGB, then fine-tune its individuals, its mean network and as many
    fresh networks; one record."""
    began = time.perf_counter()
    sweep = config.sweep
    sizes = dense_sizes(data.x_train.shape[1:], (), sweep.hidden, data.num_classes)
    setting = setting_for_ratio("sgb", sizes, config.ratio, sweep.in_types, sweep.out_types)
    sgb = cell_config(sweep, setting, seed, sweep.sgb.rho_init)
    out = train_and_evaluate(sgb, data, progress=False)
    k = sgb.eval_individuals
    plain = DenseClassifier(sizes[1:], (), data.x_train.shape[1:])
    x = data.x_train[:1]
    starts = [("mean", None, plain_params(out["model"], out["params"], x, None))]
    for i, key in enumerate(jax.random.split(jax.random.key(seed + INNATE_KEY), k)):
        starts.append(("individual", i, plain_params(out["model"], out["params"], x, key)))
    for i, key in enumerate(jax.random.split(jax.random.key(seed + FRESH_KEY), k)):
        starts.append(("fresh", i, plain.init(key, x)))
    runs = [
        {"start": name, "index": i, **fine_tune(plain, p, data, sweep, config.evaluations, seed)}
        for name, i, p in starts
    ]
    return {
        "seed": seed,
        "setting": setting,
        "compression": compression("sgb", sizes, setting, sweep.in_types, sweep.out_types),
        "innate": {name: out["accuracy"][name] for name in ("individuals", "mean_network")},
        "runs": runs,
        "git_commit": git_commit(),
        "wall_time_s": round(time.perf_counter() - began, 2),
    }


def summarise(records: list[dict]) -> list[dict[str, Any]]:
    """Per start: the steps, and at each, the test accuracy averaged over the seed's
    networks of that start, then mean and SEM over seeds (NaN with one)."""
    rows = []
    for name in STARTS:
        per_seed = np.array(
            [
                np.mean([r["accuracy"] for r in record["runs"] if r["start"] == name], axis=0)
                for record in records
            ]
        )
        spread = sem(per_seed) if len(per_seed) > 1 else np.full(per_seed.shape[1], np.nan)
        steps = next(r["steps"] for r in records[0]["runs"] if r["start"] == name)
        rows.append(
            {
                "start": name,
                "steps": steps,
                "accuracy": per_seed.mean(axis=0).tolist(),
                "accuracy_sem": np.asarray(spread).tolist(),
                "n_seeds": len(records),
            }
        )
    return rows


PROFILES: dict[str, SupervisedStartConfig] = {
    "smoke": SupervisedStartConfig(
        dataset="digits", sweep=SWEEPS["smoke"]["digits"]["sweep"], ratio=4.0, seeds=(0,)
    ),
    "cpu": SupervisedStartConfig(),
    "paper": SupervisedStartConfig(
        sweep=SWEEPS["paper"]["fashion-mnist"]["sweep"], seeds=(0, 1, 2, 3, 4)
    ),
}


def run(profile: str, out_dir: Path, progress: bool = True) -> Path:
    """Run every seed of ``profile`` not yet in its results file, writing the file after
    each."""
    recording = start(
        PROFILES, profile, out_dir, lambda config: f"innate_start_supervised_{config.dataset}"
    )
    config = recording.config
    data = load(config.dataset, seed=0)
    return train_cells(
        recording.path,
        config.seeds,
        list(recording.earlier().get("records", [])),
        (lambda seed: seed, lambda r: r["seed"]),
        lambda seed: run_seed(config, data, seed),
        lambda records: _write(recording, records),
        f"innate start supervised {config.dataset}",
        progress,
    )


def _write(recording: Recording, records: list[dict]) -> Path:
    results = {
        "dataset": recording.config.dataset,
        "records": records,
        "summary": summarise(records) if records else [],
    }
    return recording.write(results, recording.config.seeds, parts=records)


def innate_supervised_rows(results: "InnateStartSupervisedResults") -> list[Row]:
    """The supervised twin (``sgb.experiments.innate_start_supervised``): per start
    (individuals, mean network) and measure, the test accuracy less the fresh networks',
    each a seed's mean over its networks, paired by seed. The measures: over the epoch
    (the area under the accuracy curve over the steps, divided by them) and after it."""
    records = results.records
    if len(records) < 2:
        return []

    def score(record: "CurveRuns", origin: str, measure: str) -> float:
        runs = [r for r in record.runs if r.start == origin]
        if measure == "after one epoch":
            return 100 * np.mean([r.accuracy[-1] for r in runs])
        steps = np.asarray(runs[0].steps, dtype=float)
        curve = np.mean([r.accuracy for r in runs], axis=0)
        return 100 * float(np.sum(np.diff(steps) * (curve[1:] + curve[:-1]) / 2) / steps[-1])

    rows = []
    for measure in ("over the epoch", "after one epoch"):
        fresh = [score(r, "fresh", measure) for r in records]
        for origin in ("individual", "mean"):
            rows.append(
                judge(
                    "ch6.innate_start_supervised",
                    f"{results.dataset}, from {origin}, {measure}",
                    stats.paired([score(r, origin, measure) for r in records], fresh),
                    f"{len(records)} seeds, one epoch",
                )
            )
    return rows


def evidence(records: Records) -> list[Row]:
    """Fine-tuning from an innate start on Fashion-MNIST (``innate_supervised_rows``)."""
    payload = records.get("innate_start_supervised")
    return [] if payload is None else innate_supervised_rows(payload.results)


def innate_start_supervised_table(payload: "InnateStartSupervised") -> pd.DataFrame:
    """Learning from an innate start on Fashion-MNIST, one row per start: the test accuracy
    (%, mean ± SEM over seeds) at each recorded step."""
    rows = []
    for s in payload.results.summary:
        row = {"start": s.start, "seeds": s.n_seeds}
        for step, mean, spread in zip(s.steps, s.accuracy, s.accuracy_sem, strict=True):
            spread = math.nan if spread is None else spread  # one seed
            row[f"step {step} (% accuracy)"] = mean_sem(mean, spread, 100.0, 1)
        rows.append(row)
    return pd.DataFrame(rows)


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
