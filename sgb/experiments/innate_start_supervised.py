"""Chapter 6, the supervised twin of ``innate_start`` (registered as
``innate_start_supervised``): do SGB individuals learn a *new* task faster than fresh
networks? The paper's Discussion proposes it: sample individuals "from the SGB, and then
train those individual networks on various tasks with much less data than would be
required to train them from scratch".

Per seed, one SGB is trained as Figure 2's sweep trains its cell nearest ``ratio``
(``sgb.supervised_sweep.cell_config``: the sweep's config, KL per synapse, from its
rho start), on the ``genome_classes`` of Fashion-MNIST (0-4 at ``cpu``) alone. Its
K = ``eval_individuals`` individuals (the ones ``sgb.supervised.train_and_evaluate``
scores, drawn with the same keys), its mean network and K freshly initialised networks
of the same widths (the seed's own baseline) then become plain
``sgb.classifiers.DenseClassifier`` networks (``plain_params``: each individual's drawn
kernels, or the type means expanded, and the SGB's biases) and learn the other classes
(5-9, the new task) with Adam on cross-entropy, at the sweep's uncompressed-network
settings (learning rate and batch size of its ``dense`` config), every network of a seed
on the same minibatches. A task's output layer is its own: every start from the genome
takes the output layer of a fresh network (individual i fresh network i's, the mean
network fresh network 0's), so that what carries over is the hidden layers alone, and an
individual differs from its fresh partner only there. The test accuracy on the new task's classes is
recorded at every step count of ``budgets``: the learning curve, and the gain of a start
over the fresh networks at each budget.

``run`` writes ``innate_start_supervised_<dataset>_<profile>.json`` after every seed (one
record each: the SGB's innate accuracies and every fine-tuning curve), atomically; a rerun
skips the seeds it holds.

Cost (``cpu``), from the earlier one-task design measured per CPU-second on one core: an
epoch of the SGB at 10x (785 hidden types of 800) on the full training set took about 11
CPU-seconds, on half of it about 6, so its 5 epochs about 30; the 21 fine-tunings of a
seed (10 individuals, the mean network, 10 fresh) of 300 steps (one epoch of the new
task's 30,000 images) about 30: about a minute a seed with compiling.
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
from sgb.data import Dataset, load, of_classes
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
    """The SGB of Figure 2's ``sweep`` nearest ``ratio`` (our convention) trained on the
    ``genome_classes`` of ``dataset``, one for each of ``seeds``, and the step counts of
    learning the other classes at which the test accuracy is taken (``budgets``, 0 the
    start)."""

    dataset: str = "fashion-mnist"
    sweep: CompressionSweep = SWEEPS["cpu"]["fashion-mnist"]["sweep"]
    ratio: float = 10.0
    seeds: tuple[int, ...] = (0, 1, 2, 3, 4)
    genome_classes: tuple[int, ...] = (0, 1, 2, 3, 4)
    budgets: tuple[int, ...] = (0, 1, 3, 10, 30, 100, 300)

    def __post_init__(self) -> None:
        validation.instance("sweep", self.sweep, CompressionSweep)
        if self.sweep.conv_features:
            raise ValueError("the fine-tuned networks are MLPs: the sweep has no conv trunk")
        validation.positive("ratio", self.ratio)
        validation.integers("seeds", self.seeds, minimum=0)
        validation.distinct(
            "genome_classes", validation.integers("genome_classes", self.genome_classes, minimum=0)
        )
        budgets = validation.integers("budgets", self.budgets, minimum=0)
        if list(budgets) != sorted(set(budgets)) or budgets[0] != 0:
            raise ValueError(f"budgets must rise from 0 without repeats, got {self.budgets}")

    def new_task(self, num_classes: int) -> tuple[int, ...]:
        """The classes the genome never saw, which its individuals learn."""
        task = tuple(c for c in range(num_classes) if c not in self.genome_classes)
        if not task or len(task) + len(self.genome_classes) != num_classes:
            raise ValueError(
                f"genome_classes {self.genome_classes} must be some, not all, of the "
                f"{num_classes} classes"
            )
        return task


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


def with_head(params: dict, fresh: dict) -> dict:
    """``params`` of a ``DenseClassifier`` with the output layer of ``fresh`` (one of the
    same widths): a network's hidden layers, and a head started as a fresh network's."""
    layers = dict(params["params"])
    last = f"dense_{len(layers) - 1}"
    return {"params": layers | {last: fresh["params"][last]}}


def fine_tune(
    model: DenseClassifier,
    params: Any,
    data: Dataset,
    sweep: CompressionSweep,
    budgets: tuple[int, ...],
    seed: int,
) -> dict[str, Any]:
    """Adam on cross-entropy from ``params`` for the last of ``budgets`` steps (the sweep's
    dense learning rate and batch size; minibatch order from ``seed``): ``steps`` (the
    budgets) and the test ``accuracy`` after each, and the last epoch's loss."""
    dense = sweep.dense
    curve: dict[str, list] = {"steps": [], "accuracy": []}

    def record(state: Any) -> Any:
        if int(state.step) in budgets:
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
        num_steps=budgets[-1],
        seed=seed,
        hook=record,
        hook_every=1,
        progress=False,
        num_classes=data.num_classes,
    )
    return {**curve, "final_loss": history[-1]["loss"]}


def run_seed(config: SupervisedStartConfig, data: Dataset, seed: int) -> dict[str, Any]:
    """Train the seed's SGB on the genome's classes, then teach the new task to its
    individuals, its mean network and as many fresh networks; one record."""
    began = time.perf_counter()
    sweep = config.sweep
    sizes = dense_sizes(data.x_train.shape[1:], (), sweep.hidden, data.num_classes)
    setting = setting_for_ratio("sgb", sizes, config.ratio, sweep.in_types, sweep.out_types)
    sgb = cell_config(sweep, setting, seed, sweep.sgb.rho_init)
    out = train_and_evaluate(sgb, of_classes(data, config.genome_classes), progress=False)
    task = of_classes(data, config.new_task(data.num_classes))
    k = sgb.eval_individuals
    plain = DenseClassifier(sizes[1:], (), data.x_train.shape[1:])
    x = data.x_train[:1]
    fresh = [plain.init(key, x) for key in jax.random.split(jax.random.key(seed + FRESH_KEY), k)]
    starts = [
        ("mean", None, with_head(plain_params(out["model"], out["params"], x, None), fresh[0]))
    ]
    for i, key in enumerate(jax.random.split(jax.random.key(seed + INNATE_KEY), k)):
        individual = plain_params(out["model"], out["params"], x, key)
        starts.append(("individual", i, with_head(individual, fresh[i])))
    starts += [("fresh", i, params) for i, params in enumerate(fresh)]
    runs = [
        {"start": name, "index": i, **fine_tune(plain, p, task, sweep, config.budgets, seed)}
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
        dataset="digits",
        sweep=SWEEPS["smoke"]["digits"]["sweep"],
        ratio=4.0,
        seeds=(0,),
        budgets=(0, 3, 30),
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
    config = recording.config
    results = {
        "dataset": config.dataset,
        "genome_classes": list(config.genome_classes),
        "records": records,
        "summary": summarise(records) if records else [],
    }
    return recording.write(results, recording.config.seeds, parts=records)


def innate_supervised_rows(results: "InnateStartSupervisedResults") -> list[Row]:
    """The supervised twin (``sgb.experiments.innate_start_supervised``): per budget of
    learning the new task (after the start) and per start (individuals, mean network), the
    test accuracy less the fresh networks' (points), each a seed's mean over its networks,
    paired by seed."""
    records = results.records
    if len(records) < 2:
        return []
    task = new_task_text(results)

    def at(record: "CurveRuns", origin: str, j: int) -> float:
        return 100 * float(np.mean([r.accuracy[j] for r in record.runs if r.start == origin]))

    steps = records[0].runs[0].steps
    rows = []
    for j, budget in enumerate(steps):
        if budget == 0:
            continue
        fresh = [at(r, "fresh", j) for r in records]
        for origin in ("individual", "mean"):
            rows.append(
                judge(
                    "ch6.innate_start_supervised",
                    f"{results.dataset} {task}, from {origin}, after {budget} steps",
                    stats.paired([at(r, origin, j) for r in records], fresh),
                    f"{len(records)} seeds, each with its own fresh networks",
                )
            )
    return rows


def new_task_text(results: "InnateStartSupervisedResults") -> str:
    """The task learned, as the rows name it: ``classes 5-9 (genome on 0-4)``."""
    seen = results.genome_classes
    return f"classes {_span(c for c in range(10) if c not in seen)} (genome on {_span(seen)})"


def _span(classes) -> str:
    classes = list(classes)
    return (
        f"{classes[0]}-{classes[-1]}"
        if classes == list(range(classes[0], classes[-1] + 1))
        else ",".join(map(str, classes))
    )


def evidence(records: Records) -> list[Row]:
    """Fine-tuning from an innate start on Fashion-MNIST (``innate_supervised_rows``)."""
    payload = records.get("innate_start_supervised")
    return [] if payload is None else innate_supervised_rows(payload.results)


def innate_start_supervised_table(payload: "InnateStartSupervised") -> pd.DataFrame:
    """Learning a new task from an innate start, one row per start: the test accuracy on
    the new task's classes (%, mean ± SEM over seeds) at each budget of steps."""
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
    genome_classes: list[int]
    records: MaybeEmpty[CurveRuns]
    summary: List[CurveSummary]


class InnateStartSupervised(ResultsFile):
    results: InnateStartSupervisedResults
