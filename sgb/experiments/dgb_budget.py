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

import dataclasses
import json
import time
from collections.abc import Iterator
from pathlib import Path

from tqdm.auto import tqdm

from sgb import resume, validation
from sgb.classifiers import dense_sizes
from sgb.compression import CONVENTIONS, compression, setting_for_ratio
from sgb.data import Dataset, load
from sgb.dgb import DGB, DGBConfig, dgb_for, train_dgb
from sgb.provenance import _jsonable, git_commit
from sgb.recording import Recording, start
from sgb.supervised import DenseConfig, at_chance, dense_accuracy, train_and_evaluate


@dataclasses.dataclass(frozen=True)
class BudgetConfig:
    """One DGB at compression ``ratio`` (our convention; input and output types as in
    Figure 2's sweep, for the ratio's bookkeeping only), trained ``dgb.rounds`` rounds
    in chunks of ``chunk_rounds``, on the data named ``dataset`` (the name ``run`` loads,
    ``sgb.data.load``; ``train_with_budget`` takes the data themselves)."""

    dataset: str = "fashion-mnist"
    ratio: float = 10.0
    dgb: DGBConfig = DGBConfig(rounds=500)
    chunk_rounds: int = 25
    in_types: int = 30
    out_types: int = 10

    @property
    def types(self) -> tuple[int, int]:
        return self.in_types, self.out_types

    def __post_init__(self) -> None:
        validation.instance("dataset", self.dataset, str)
        validation.positive("ratio", self.ratio)
        validation.instance("dgb", self.dgb, DGBConfig)
        validation.integer("chunk_rounds", self.chunk_rounds)
        if self.dgb.rounds % self.chunk_rounds:
            raise ValueError(
                f"dgb.rounds={self.dgb.rounds} must be a multiple of "
                f"chunk_rounds={self.chunk_rounds}"
            )


def sizes_and_width(config: BudgetConfig, data: Dataset) -> tuple[tuple[int, ...], int]:
    """The dense layer sizes on ``data`` and the g-net width whose compression (our
    convention, the DGB's layout) is nearest ``config.ratio``."""
    sizes = dense_sizes(data.x_train.shape[1:], (), config.dgb.hidden, data.num_classes)
    layout = config.dgb.layout
    return sizes, setting_for_ratio("dgb", sizes, config.ratio, *config.types, layout=layout)


def _generated_accuracy(dgb: DGB, state, data: Dataset) -> float:
    """Test accuracy of the network the g-nets generate now (biases from the p-net)."""
    params = dgb.with_generated(state.pnet.params, state.gnets)
    return dense_accuracy(dgb.model, params, data.x_test, data.y_test)


def train_with_budget(
    config: BudgetConfig, data: Dataset, state_file: Path | None = None
) -> Iterator[dict]:
    """Yield a record after every chunk of ``config.chunk_rounds`` rounds,
    continuing from ``state_file`` if it holds a state of this run (and saving it there
    after every chunk). A record: ``rounds``, ``best_validation_accuracy``,
    ``test_accuracy`` (the best network's), ``at_chance`` (whether that is no better than
    chance, ``sgb.supervised.at_chance``), ``generated_test_accuracy``, ``fit_mse``.
    A damaged state file, or one whose networks are not finite, is a
    ``sgb.validation.CorruptFile`` naming it."""
    _, width = sizes_and_width(config, data)
    dgb_config = dataclasses.replace(config.dgb, gnet_width=width, rounds=config.chunk_rounds)
    dgb = dgb_for(dgb_config, data.x_train.shape[1:], data.num_classes)
    run = json.loads(json.dumps({"config": _jsonable(config), "gnet_width": width}))
    state, progress = dgb.init(data.x_train), {"records": []}
    if state_file is not None and state_file.exists():
        state, progress = resume.load(
            state_file,
            state,
            run,
            progress_keys=("records",),
            finite=lambda state: (state.pnet.params, state.gnets, state.best_params),
        )
    records = progress["records"]
    if records:
        print(
            f"DGB budget: resuming from {state_file} after {int(state.rounds)} rounds", flush=True
        )
    yield from records
    commit = git_commit()  # the code this process runs, whatever is committed meanwhile
    while int(state.rounds) < config.dgb.rounds:
        start = time.perf_counter()
        _, state, _ = train_dgb(dgb_config, data, progress=False, state=state)
        test_accuracy = dense_accuracy(dgb.model, state.best_params, data.x_test, data.y_test)
        record = {
            "rounds": int(state.rounds),
            "gnet_width": width,
            "best_validation_accuracy": float(state.best_accuracy),
            "test_accuracy": test_accuracy,
            "at_chance": at_chance(test_accuracy, data.y_test),
            "generated_test_accuracy": _generated_accuracy(dgb, state, data),
            "fit_mse": float(state.fit_mse),
            "wall_time_s": round(time.perf_counter() - start, 2),
            "git_commit": commit,
        }
        records.append(record)
        if state_file is not None:
            resume.save(state_file, state, run, {"records": records})
        yield record


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
