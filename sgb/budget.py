"""One DGB trained for a budget of rounds (the authors' settings by default), in chunks:
after each, the best validation accuracy so far, the test accuracy of that best network
and of the network the g-nets generate now, with its training state saved so that a
killed run continues where it stopped (``sgb.resume``).
"""

import dataclasses
import json
import time
from collections.abc import Iterator
from pathlib import Path

from sgb import resume, validation
from sgb.classifiers import dense_sizes
from sgb.compression import setting_for_ratio
from sgb.data import Dataset
from sgb.dgb import DGB, DGBConfig, dgb_for, train_dgb
from sgb.provenance import git_commit, jsonable
from sgb.supervised import at_chance, dense_accuracy


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
    run = json.loads(json.dumps({"config": jsonable(config), "gnet_width": width}))
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
