"""Nothing lost, nothing silently wrong: atomic strict-JSON results, profile-named files,
output locations checked first, and training that stops on divergence."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from sgb import provenance
from sgb.__main__ import main
from sgb.data import digits
from sgb.dgb import DGBConfig
from sgb.divergence import TrainingDiverged
from sgb.provenance import read_results, results_file
from sgb.recording import write_results
from sgb.supervised import ClassifierConfig, DenseConfig, train_and_evaluate, train_classifier


def test_a_failed_write_leaves_the_old_results_intact(tmp_path, monkeypatch):
    path = write_results(tmp_path / "fig_cpu.json", {"accuracy": [0.9, 0.8]}, {"profile": "cpu"})
    old = path.read_bytes()
    real_fdopen = os.fdopen

    class HalfWriter:
        """A file that writes half of what it is given, then fails (a full disk)."""

        def __init__(self, handle):
            self.handle = handle

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.handle.close()

        def write(self, data):
            self.handle.write(data[: len(data) // 2])
            raise OSError(28, "No space left on device")

    monkeypatch.setattr(provenance.os, "fdopen", lambda fd, mode: HalfWriter(real_fdopen(fd, mode)))
    with pytest.raises(OSError, match="No space"):
        write_results(path, {"accuracy": [0.1] * 10_000}, {"profile": "cpu"})
    assert path.read_bytes() == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig_cpu.json"]  # no temporary left


def test_results_are_strict_json_with_null_for_non_finite_numbers(tmp_path):
    results = {"sem": float("nan"), "values": np.array([1.0, np.inf]), "n": 1}
    path = write_results(tmp_path / "x_cpu.json", results, {"profile": "cpu"})

    def reject(constant):
        raise AssertionError(f"non-standard JSON constant {constant}")

    payload = json.loads(path.read_text(), parse_constant=reject)
    assert payload["results"] == {"sem": None, "values": [1.0, None], "n": 1}
    assert "null" in provenance.provenance({}, "cpu", [0], 0.0)


def test_each_profile_has_its_own_file_and_a_bad_location_fails_first(tmp_path):
    names = {results_file(tmp_path, "theory", p).name for p in ("smoke", "cpu", "paper")}
    assert names == {"theory_smoke.json", "theory_cpu.json", "theory_paper.json"}
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    with pytest.raises(ValueError, match="cannot write results under"):
        results_file(blocker / "sub", "theory", "cpu")


def test_cli_rejects_an_unwritable_out_dir_before_running(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    # bbb would train for minutes; the location is refused before any training
    assert main(["reproduce", "bbb", "--out-dir", str(blocker / "out")]) == 2
    assert "cannot write results under" in capsys.readouterr().err


def _small_digits():
    data = digits(seed=0)
    return data._replace(x_train=data.x_train[:256], y_train=data.y_train[:256])


def test_sgb_training_stops_on_divergence_and_reports_no_accuracy():
    config = ClassifierConfig(hidden=(16,), learning_rate=1e30, epochs=2, batch_size=64)
    with pytest.raises(TrainingDiverged, match=r"at step \d+"):
        train_classifier(config, _small_digits(), progress=False)


@pytest.mark.parametrize(
    "config",
    [
        DenseConfig(hidden=(16,), learning_rate=1e30, epochs=2),
        DGBConfig(
            hidden=(16,),
            gnet_width=4,
            learning_rate=1e30,
            rounds=2,
            pnet_steps=4,
            batch_size=64,
            gnet_steps=5,
            validation_size=32,
        ),
    ],
)
def test_dense_and_dgb_training_stop_on_divergence(config):
    with pytest.raises(TrainingDiverged, match=r"at step \d+"):
        train_and_evaluate(config, _small_digits(), progress=False)


def test_committed_results_are_strict_json():
    def reject(constant):
        raise AssertionError(f"non-standard JSON constant {constant}")

    root = Path(__file__).resolve().parents[1] / "results"
    files = sorted(root.rglob("*_cpu.json")) + sorted(root.rglob("bench_*.json"))
    assert files
    for path in files:
        json.loads(path.read_text(), parse_constant=reject)
        assert read_results(path)
