"""A results file is read only as its run wrote it: the checksum a run embeds in its
provenance (``sgb.provenance``) and the manifest of the committed results
(``sgb.manifest``), written by the runs and by a maintainer's checked command."""

import json
import shutil
import threading

import pytest

from sgb import gather, manifest, provenance
from sgb.paths import committed_results
from sgb.provenance import read_results
from sgb.recording import earlier_results, write_results
from sgb.validation import CorruptFile

RUN = {"config": {"lr": 0.1}, "profile": "cpu", "seeds": [0]}


@pytest.fixture
def committed(tmp_path, monkeypatch):
    """A stand-in for the committed results directory, empty."""
    root = tmp_path / "results"
    root.mkdir()
    monkeypatch.setattr(manifest, "committed_results", lambda: root)
    return root


def _edit_one_number(path, old: str, new: str) -> None:
    """Replace the first ``old`` in ``path``'s text by ``new``, as an edit by hand would."""
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))


def test_a_run_embeds_the_checksum_of_its_payload_and_a_reader_checks_it(tmp_path):
    path = write_results(tmp_path / "x_cpu.json", {"acc": [0.5, 0.25]}, RUN)
    payload = read_results(path)
    assert payload["provenance"][provenance.CHECKSUM] == provenance.payload_digest(payload)
    provenance.verify_checksum(path, payload, "rerun it")
    _edit_one_number(path, "0.25", "0.35")
    with pytest.raises(CorruptFile, match=r"x_cpu\.json is not as its run wrote it"):
        provenance.verify_checksum(path, read_results(path), "rerun it")
    # a rerun into its own --out-dir continues from a file pruned by hand
    assert earlier_results(path, RUN["config"]) == {"acc": [0.5, 0.35]}


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ('{"provenance": {}, "results": {"x": NaN}}', "NaN is not a finite number"),
        ('{"provenance": {}, "results": {"x": 1e999}}', "1e999 is not a finite number"),
        ('{"provenance": {}, "results"', "is not a results file"),
        ('{"results": {}}', 'has no "provenance" object'),
        ('{"provenance": {}}', 'has no "results" object'),
        ("[1, 2]", 'has no "provenance" object'),
        ('{"results": {}, "provenance": {}}', "has no config in its provenance"),
    ],
)
def test_an_earlier_file_that_is_not_a_results_file_stops_a_rerun_naming_it(
    tmp_path, text, problem
):
    """What ``reproduce fig2`` meets in an --out-dir holding ``{"results": {}}``, and the
    like: an error that names the file and says to run afresh."""
    path = tmp_path / "fig2_digits_cpu.json"
    path.write_text(text)
    with pytest.raises(CorruptFile, match=problem) as error:
        earlier_results(path, {"lr": 0.1})
    assert error.value.path == path and "run again" in str(error.value)


def test_the_scorecard_names_a_committed_file_without_provenance_or_results(tmp_path):
    (tmp_path / "rl").mkdir()
    for part in ("provenance", "results"):
        payload = json.loads((committed_results() / "rl" / "fig5_ant_cpu.json").read_text())
        del payload[part]
        (tmp_path / "rl" / "fig5_ant_cpu.json").write_text(json.dumps(payload))
        with pytest.raises(CorruptFile, match=f"fig5_ant_cpu.json has no {part}; restore it"):
            gather.scorecard(tmp_path)


def test_a_directory_in_place_of_a_results_file_is_refused(tmp_path):
    (tmp_path / "rl" / "fig5_ant_cpu.json").mkdir(parents=True)
    with pytest.raises(CorruptFile, match=r"fig5_ant_cpu\.json is a directory"):
        gather.records(tmp_path)("fig5")


def test_a_run_into_the_committed_results_enters_its_file_and_no_other(committed, tmp_path):
    path = write_results(committed / "rl" / "x_ant_cpu.json", {"acc": [0.5]}, RUN)
    write_results(committed / "x_digits_smoke.json", {"acc": [0.5]}, RUN)
    write_results(committed / "rl" / "checkpoints" / "x_cpu.json", {"acc": [0.5]}, RUN)
    write_results(tmp_path / "elsewhere_cpu.json", {"acc": [0.5]}, RUN)
    assert manifest.entries(committed) == {"rl/x_ant_cpu.json": manifest.digest(path)}
    manifest.verify(path)
    assert earlier_results(path, RUN["config"]) == {"acc": [0.5]}


def test_a_one_number_edit_of_a_committed_file_is_refused_naming_it(committed):
    path = write_results(committed / "rl" / "x_ant_cpu.json", {"returns": [1520.5, 980.25]}, RUN)
    _edit_one_number(path, "980.25", "9980.25")
    payload = json.loads(path.read_text())
    del payload["provenance"][provenance.CHECKSUM]  # an edit that hides from the checksum too
    path.write_text(json.dumps(payload, indent=1))
    with pytest.raises(CorruptFile, match="differs from its entry") as error:
        manifest.verify(path)
    assert error.value.path == path and "x_ant_cpu.json" in str(error.value)
    with pytest.raises(CorruptFile, match="differs from its entry"):
        earlier_results(path, RUN["config"])  # a rerun does not continue from it either


def test_a_committed_file_without_an_entry_or_without_a_manifest_is_refused(committed):
    path = write_results(committed / "x_digits_cpu.json", {"acc": [0.5]}, RUN)
    copied = committed / "y_digits_cpu.json"
    shutil.copy(path, copied)
    with pytest.raises(CorruptFile, match="has no entry in .*python -m sgb manifest"):
        manifest.verify(copied)
    (committed / manifest.NAME).unlink()
    with pytest.raises(CorruptFile, match="MANIFEST.json is missing"):
        manifest.verify(path)


def test_writers_of_different_files_at_once_keep_every_entry(committed):
    def write(worker: int) -> None:
        for i in range(5):
            write_results(committed / f"w{worker}_{i}_cpu.json", {"worker": [worker, i]}, RUN)

    workers = [threading.Thread(target=write, args=(w,)) for w in range(6)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join()
    written = manifest.entries(committed)
    assert len(written) == 30
    assert all(written[p.name] == manifest.digest(p) for p in committed.glob("w*_cpu.json"))


def _arrived(committed, **record) -> object:
    """A results file a run at this repository's HEAD wrote elsewhere, copied in."""
    commit = provenance.git_commit()
    run = RUN | {"git_commit": commit, "date": "2026-12-04", "wall_time_s": 1.0, "backend": "gpu"}
    return write_results(committed / "theory_cpu.json", _theory(), run | record)


def _theory() -> dict:
    return read_results(committed_results() / "theory_cpu.json")["results"]


def test_a_maintainer_enters_a_file_from_elsewhere_once_it_is_checked(committed, capsys):
    path = _arrived(committed)
    (committed / manifest.NAME).unlink()  # as a copy would arrive: not in the manifest
    assert manifest.main([str(path)], gather.model_of) == 2
    assert "--maintainer-write-committed" in capsys.readouterr().err
    assert not (committed / manifest.NAME).exists()
    assert manifest.main([str(path), "--maintainer-write-committed"], gather.model_of) == 0
    assert manifest.entries(committed) == {"theory_cpu.json": manifest.digest(path)}
    theory = gather.records(committed)("theory")
    assert theory.model_dump(exclude_unset=True)["results"] == _theory()


@pytest.mark.parametrize(
    ("damage", "problem"),
    [
        ("commit", "names commit '0000000000000000000000000000000000000000', which is not"),
        ("checksum", "is not as its run wrote it"),
        ("schema", r"has results\.trajectories\.convex\.gap\[0\] = null"),
    ],
)
def test_a_maintainer_cannot_enter_a_file_that_fails_a_check(committed, damage, problem):
    path = _arrived(committed, git_commit="0" * 40) if damage == "commit" else _arrived(committed)
    payload = json.loads(path.read_text())
    payload["results"]["trajectories"]["convex"]["gap"][0] = None
    if damage == "schema":
        payload["provenance"][provenance.CHECKSUM] = provenance.payload_digest(payload)
    if damage != "commit":
        path.write_text(json.dumps(payload))
    (committed / manifest.NAME).unlink()
    with pytest.raises(CorruptFile, match=problem) as error:
        manifest.add([path], gather.model_of)
    assert error.value.path == path
    assert not (committed / manifest.NAME).exists()


def test_the_maintainer_command_takes_only_results_files_of_the_committed_results(
    committed, tmp_path
):
    outside = write_results(tmp_path / "theory_cpu.json", {"x": [1]}, RUN)
    sidecar = write_results(committed / "rl" / "checkpoints" / "a_cpu.json", {"x": [1]}, RUN)
    for path in (outside, sidecar):
        with pytest.raises(ValueError, match="is not a results file of the committed results"):
            manifest.add([path], gather.model_of)
