"""The one way runs are recorded: profile checks, resuming, wall time and commits of parts."""

import dataclasses

import pytest

from sgb.provenance import read_results
from sgb.recording import held_results, start, superseding


@dataclasses.dataclass(frozen=True)
class Toy:
    dataset: str
    epochs: int


PROFILES = {"smoke": Toy("digits", 1), "cpu": Toy("digits", 5), "paper": Toy("mnist", 50)}


def test_bad_profile_or_choice_fails_before_any_file(tmp_path):
    with pytest.raises(ValueError, match="unknown profile 'fast'"):
        start(PROFILES, "fast", tmp_path, "toy")
    per_dataset = {p: {"digits": config} for p, config in PROFILES.items()}
    with pytest.raises(ValueError, match=r"'mnist' has no cpu profile.*\['digits'\]"):
        start(per_dataset, "cpu", tmp_path, "toy", choice="mnist")
    assert start(per_dataset, "cpu", tmp_path, "toy", choice="digits").config == PROFILES["cpu"]
    assert list(tmp_path.iterdir()) == []


def test_parts_give_the_wall_time_and_commits_and_a_rerun_resumes(tmp_path):
    recording = start(PROFILES, "cpu", tmp_path, lambda config: f"toy_{config.dataset}")
    assert recording.path == tmp_path / "toy_digits_cpu.json"
    assert recording.earlier() == {}
    parts = [
        {"wall_time_s": 1.5, "git_commit": "b"},
        {"wall_time_s": 2.25, "git_commit": "a"},
        {"wall_time_s": 4.0, "git_commit": "b"},
    ]
    recording.write({"parts": parts}, seeds=(0, 1), parts=parts)
    provenance = read_results(recording.path)["provenance"]
    assert provenance["wall_time_s"] == 7.75
    assert provenance["git_commits"] == ["a", "b"]
    assert provenance["seeds"] == [0, 1]
    assert provenance["config"] == {"type": "Toy", "dataset": "digits", "epochs": 5}

    again = start(PROFILES, "cpu", tmp_path, lambda config: f"toy_{config.dataset}")
    assert again.earlier() == {"parts": parts}
    other = dataclasses.replace(recording, config=Toy("digits", 6))
    with pytest.raises(ValueError, match="another config"):
        other.earlier()
    # a listing of what is still to do reads a file of another design as nothing done
    assert held_results(recording.path, Toy("digits", 6)) == {}
    assert held_results(recording.path, Toy("digits", 5)) == {"parts": parts}
    # the queue's workers replace it: the run of the new design starts afresh
    with superseding():
        assert held_results(recording.path, Toy("digits", 6)) == {}
        assert recording.path.exists()  # a listing never deletes
        assert other.earlier() == {}
    assert not recording.path.exists()
    assert again.earlier() == {}


def test_a_run_without_parts_is_timed_from_its_start(tmp_path):
    recording = start(PROFILES, "smoke", tmp_path, "toy")
    recording = dataclasses.replace(recording, began=recording.began - 30.0)
    recording.write({"value": 1}, seeds=[0])
    provenance = read_results(recording.path)["provenance"]
    assert provenance["wall_time_s"] >= 30.0
    assert "git_commits" not in provenance
