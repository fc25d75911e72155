"""The results-reading layer (``sgb.results``) gives the committed files' own values."""

import shutil

import pytest
from committed import RECORDS, raw

from sgb import gather, manifest, results, schemas
from sgb.experiments import fig3 as fig3_runs
from sgb.paths import committed_results
from sgb.validation import CorruptFile


def test_load_reads_the_committed_file_as_its_record_and_names_a_missing_one(tmp_path):
    record = results.load("rl/fig3_ant_cpu.json", fig3_runs.Fig3)
    assert isinstance(record.results.runs[0], fig3_runs.Fig3Run)
    assert record.model_dump(exclude_unset=True) == raw("rl/fig3_ant_cpu.json")
    assert results.path("theory_cpu.json") == committed_results() / "theory_cpu.json"
    assert results.load("absent.json", fig3_runs.Fig3, tmp_path, missing_ok=True) is None
    with pytest.raises(FileNotFoundError, match="absent.json"):
        results.load("absent.json", fig3_runs.Fig3, tmp_path)


def _committed_files() -> list[str]:
    """The names of every results file under the committed results that the manifest keeps."""
    root = committed_results()
    names = (p.relative_to(root).as_posix() for p in root.rglob("*.json"))
    return sorted(n for n in names if manifest.covers(n))


def test_every_committed_results_file_matches_the_manifest_and_its_schema():
    """What the book's build reads: every file is in the manifest as its run wrote it (and
    the manifest names no other), and parses under its schema."""
    names = _committed_files()
    assert len(names) >= 20 and "rl/bench_rl.json" in names
    assert sorted(manifest.entries(committed_results())) == names
    for name in names:
        assert results.load(name, gather.model_of(name)).model_dump(exclude_unset=True) == raw(name)
    with pytest.raises(ValueError, match="no experiment or benchmark declares"):
        gather.model_of("rl/unknown_ant_cpu.json")


def test_the_manifest_refuses_a_one_number_edit_of_a_committed_file(tmp_path):
    """A copy of the committed Figure 5 file and the manifest reads as the committed one;
    one return changed by hand (to 1e308, which swings a verdict) and it is refused, by name."""
    shutil.copy(committed_results() / manifest.NAME, tmp_path)
    (tmp_path / "rl").mkdir()
    copy = tmp_path / "rl" / "fig5_ant_cpu.json"
    shutil.copy(committed_results() / "rl" / "fig5_ant_cpu.json", copy)
    assert [r.key for r in gather.scorecard(tmp_path)][:2] == ["fig5.population_beats_mean"] * 2
    payload = raw("rl/fig5_ant_cpu.json")
    first = payload["results"]["authors_protocol"]["individuals"][0][0]
    text = copy.read_text()
    assert text.count(repr(first)) == 1
    copy.write_text(text.replace(repr(first), "1e308"))
    with pytest.raises(CorruptFile, match="differs from its entry in") as error:
        gather.scorecard(tmp_path)
    assert error.value.path == copy
    assert "fig5_ant_cpu.json" in str(error.value) and "--maintainer-write-committed" in str(
        error.value
    )
    (tmp_path / manifest.NAME).unlink()  # a directory without a manifest: the schema refuses it
    with pytest.raises(CorruptFile, match=r"individuals\[0\]\[0\] = 1e\+308: Input should be less"):
        gather.scorecard(tmp_path)


def test_provenance_line_names_profile_seeds_commits_date_and_wall_time():
    payload = raw("fig2_fashion-mnist_cpu.json")
    record = payload["provenance"]
    line = results.provenance_line(RECORDS("fig2"))
    assert "\n" not in line
    assert line.startswith(f"profile {record['profile']}, seeds {record['seeds']}, ")
    assert all(commit[:10] in line for commit in record["git_commits"])
    commits = ["9dbd713a4e" + "0" * 30, "9dbd713a4e" + "0" * 30 + "+dirty", "c7ecc8e69f" * 4]
    mixed = {**payload, "provenance": {**record, "git_commits": commits}}
    several = results.provenance_line(schemas.ResultsFile.model_validate(mixed))
    assert several.count("9dbd713a4e,") == 1 and "9dbd713a4e+dirty" in several  # each once
    assert "c7ecc8e69f" in several
    assert record["date"][:10] in line
    assert f"{record['wall_time_s'] / 60:.0f} min on {record['backend']}" in line


@pytest.mark.parametrize(
    ("seconds", "shown"), [(313.1, "5 min"), (59.6, "60 s"), (28236.56, "7.8 h")]
)
def test_provenance_line_gives_the_wall_time_in_a_readable_unit(seconds, shown):
    made = {"profile": "cpu", "seeds": [0], "git_commit": "0123456789abcdef", "backend": "cpu"}
    made |= {"config": {}, "date": "2026-12-01T20:18:05+00:00", "wall_time_s": seconds}
    line = results.provenance_line(schemas.ResultsFile.model_validate({"provenance": made}))
    assert line == f"profile cpu, seeds [0], commit 0123456789, 2026-12-01, {shown} on cpu"
