"""The DGB at the lowest compression of Figure 2, trained for the authors' budget.

Figure 2's ``cpu`` sweep trains every DGB for 100 short rounds; this experiment asks
whether that budget, not the g-net's capacity, is what keeps the DGB below the
uncompressed network. It trains one DGB (g-net width for ``ratio``, our convention)
with the authors' settings (``sgb.dgb.DGBConfig`` defaults: 100 p-net minibatches of
100 and 600 g-net steps of 1000 synapses a round, 10,000 validation images) for
``rounds`` rounds, and after every ``chunk_rounds`` rounds records the best
validation accuracy so far and the test accuracy of that best network (the innate
one), and of the network the g-nets generate now. The uncompressed network is then
trained for as many minibatches as the DGB's p-net saw (``same_budget_dense``).

``run`` writes ``dgb_budget_<dataset>_<profile>.json`` after every chunk, atomically,
with provenance, and keeps the training state beside it (``*.state.npz``), so a killed
run continues where it stopped; the state file is removed when the run ends.
"""

import time
from pathlib import Path

import pandas as pd
from tqdm.auto import tqdm

from sgb.budget import BudgetConfig, sizes_and_width, train_with_budget
from sgb.compression import CONVENTIONS, compression
from sgb.data import Dataset, load
from sgb.dgb import DGBConfig
from sgb.prose import Card, percent
from sgb.provenance import git_commit
from sgb.recording import Recording, start
from sgb.results import Records
from sgb.schemas import Accuracy, Compression, Count, DgbRecord, List, Record, ResultsFile
from sgb.supervised import DenseConfig, train_and_evaluate

PROFILES: dict[str, BudgetConfig] = {
    "smoke": BudgetConfig(
        dataset="digits",
        ratio=4.0,
        dgb=DGBConfig(
            hidden=(64,), rounds=4, pnet_steps=5, batch_size=32, gnet_steps=5, validation_size=200
        ),
        chunk_rounds=2,
    ),
    "cpu": BudgetConfig(),
    "paper": BudgetConfig(),
}


def same_budget_dense(config: BudgetConfig, data: Dataset) -> dict:
    """The uncompressed network trained for as many minibatches as the DGB's p-net sees
    (``rounds`` x ``pnet_steps`` of ``batch_size``, rounded to whole epochs): its test
    accuracy (and ``at_chance``), epochs, wall time and commit."""
    steps = config.dgb.rounds * config.dgb.pnet_steps * config.dgb.batch_size
    epochs = max(1, round(steps / len(data.x_train)))
    dense = DenseConfig(
        hidden=config.dgb.hidden,
        learning_rate=config.dgb.learning_rate,
        batch_size=config.dgb.batch_size,
        epochs=epochs,
        seed=config.dgb.seed,
    )
    start = time.perf_counter()
    out = train_and_evaluate(dense, data, progress=False)
    return {
        "epochs": epochs,
        "accuracy": out["accuracy"],
        "at_chance": out["at_chance"],
        "wall_time_s": round(time.perf_counter() - start, 2),
        "git_commit": git_commit(),
    }


def run(profile: str, out_dir: Path, progress: bool = True) -> Path:
    """Train the DGB of ``profile`` and the uncompressed network for the same budget, and
    write the DGB's learning record and both accuracies with provenance. A finished part
    is read back from the results file, not trained again."""
    recording = start(PROFILES, profile, out_dir, lambda config: f"dgb_budget_{config.dataset}")
    config, path = recording.config, recording.path
    state_file = path.with_suffix(".state.npz")
    results = recording.earlier()
    data = load(config.dataset, seed=0)
    sizes, width = sizes_and_width(config, data)
    chunks = config.dgb.rounds // config.chunk_rounds
    if progress and len(results.get("records", [])) == chunks:
        print(f"DGB budget: reusing the finished DGB run in {path}", flush=True)
    if len(results.get("records", [])) < chunks:
        results = {
            "dataset": config.dataset,
            "sizes": list(sizes),
            **{
                f"compression_{c}": compression(
                    "dgb", sizes, width, *config.types, c, config.dgb.layout
                )
                for c in CONVENTIONS
            },
            "records": [],
        }
        for record in tqdm(
            train_with_budget(config, data, state_file),
            desc=f"DGB rounds of {config.chunk_rounds}",
            total=chunks,
            disable=not progress,
        ):
            results["records"].append(record)
            _write(recording, results)
        state_file.unlink(missing_ok=True)
    if "uncompressed_same_budget" not in results:
        results["uncompressed_same_budget"] = same_budget_dense(config, data)
        _write(recording, results)
    return path


def _write(recording: Recording, results: dict) -> Path:
    dense = results.get("uncompressed_same_budget")
    parts = results["records"] + ([dense] if dense else [])
    return recording.write(results, [recording.config.dgb.seed], parts=parts)


def dgb_budget(results: "DgbBudgetResults", dense_accuracy: float) -> dict[str, str]:
    """The DGB budget run (``dgb_budget_fashion-mnist_cpu.json``'s results): test accuracy
    after 25, 100, 250 and 500 rounds (``budget_25``, ...), the first round within 3 points
    of ``dense_accuracy`` (a fraction; ``budget_near_rounds``), the best validation at 500
    (``budget_val_500``) and the uncompressed network at the same budget (``budget_same``,
    ``budget_same_epochs``)."""
    records = results.records
    at = {r.rounds: r for r in records}
    near = next(r for r in records if r.test_accuracy >= dense_accuracy - 0.03)
    same = results.uncompressed_same_budget
    texts = {f"budget_{n}": percent(at[n].test_accuracy) for n in (25, 100, 250, 500)}
    return texts | {
        "budget_near_rounds": str(near.rounds),
        "budget_val_500": percent(at[500].best_validation_accuracy),
        "budget_same": percent(same.accuracy),
        "budget_same_epochs": str(same.epochs),
    }


def texts(records: Records, card: Card) -> dict[str, str]:
    """What chapter 4 glues of the DGB at the authors' budget (``dgb_budget``), beside the
    uncompressed network of Figure 2's cpu sweep."""
    dense = records("fig2").results.ours.summary.dense.mean[0]
    return dgb_budget(records("dgb_budget").results, dense)


def dgb_budget_table(results: "DgbBudgetResults") -> pd.DataFrame:
    """The DGB budget run (``sgb.experiments.dgb_budget``), one row per recorded round:
    best validation accuracy, its network's test accuracy and the generated network's (%)."""
    return pd.DataFrame(
        {
            "rounds": r.rounds,
            "best validation %": 100 * r.best_validation_accuracy,
            "its test %": 100 * r.test_accuracy,
            "generated test %": 100 * r.generated_test_accuracy,
        }
        for r in results.records
    )


class SameBudget(Record):
    epochs: Count
    accuracy: Accuracy


class BudgetRound(DgbRecord):
    """A recorded round of the DGB, with its g-net's width."""

    gnet_width: Count


class DgbBudgetResults(Record):
    dataset: str
    compression_ours: Compression
    records: List[BudgetRound]
    uncompressed_same_budget: SameBudget


class DgbBudget(ResultsFile):
    results: DgbBudgetResults
