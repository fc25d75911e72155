"""``python -m sgb reproduce``: where results go, the committed results kept out of reach
without the maintainer flag, what a rerun keeps and says it reuses, what a run says it is,
the arguments checked before anything runs, and a ``--help`` that describes every
experiment by chapter."""

import dataclasses
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import jax
import pytest

import sgb.__main__
from sgb.__main__ import build_parser, experiments_help, jax_backend, main
from sgb.experiments import CHAPTERS, EXPERIMENTS, bayes_by_backprop, fig2
from sgb.manifest import MAINTAINER_FLAG
from sgb.paths import committed_results
from sgb.profiles import PROFILE_NAMES
from sgb.provenance import git_commit
from sgb.recording import start, write_results

ROOT = Path(__file__).resolve().parent.parent


def _committed_state() -> dict[str, tuple[int, int]]:
    """Size and modification time of every committed results file a supervised experiment
    could write (results/ outside rl/), and the names of any smoke files anywhere under it.
    (rl/ is left out of the first: a maintainer's sweep may be writing it meanwhile.)"""
    root = committed_results()
    state = {}
    for path in root.rglob("*"):
        name = path.relative_to(root).as_posix()
        if path.is_file() and (not name.startswith("rl/") or "_smoke" in path.name):
            state[name] = (path.stat().st_size, path.stat().st_mtime_ns)
    return state


@pytest.mark.parametrize("inside", ["", "rl"])
def test_the_committed_results_are_refused_without_the_maintainer_flag(inside, capsys):
    before = _committed_state()
    out_dir = committed_results() / inside
    assert main(["reproduce", "bbb", "--out-dir", str(out_dir)]) == 2
    error = capsys.readouterr().err
    assert "the committed results" in error and MAINTAINER_FLAG in error
    assert _committed_state() == before


def test_sgb_results_naming_the_committed_results_is_refused_too(monkeypatch, capsys):
    monkeypatch.setenv("SGB_RESULTS", str(committed_results()))
    assert main(["reproduce", "bbb"]) == 2
    assert MAINTAINER_FLAG in capsys.readouterr().err


def test_the_maintainer_flag_writes_only_into_the_committed_results(tmp_path, capsys):
    assert main(["reproduce", "bbb", MAINTAINER_FLAG, "--out-dir", str(tmp_path)]) == 2
    assert "takes no other --out-dir" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_a_smoke_reproduce_writes_to_sgb_results_and_leaves_the_committed_results(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("SGB_RESULTS", raising=False)
    before = _committed_state()
    assert main(["reproduce", "dgb_budget", "--profile", "smoke"]) == 0
    written = Path("sgb-results") / "dgb_budget_digits_smoke.json"
    out = capsys.readouterr().out
    assert f"wrote {written}" in out and "reusing what an earlier run" not in out
    assert (
        f"dgb_budget_digits, smoke profile, commit {git_commit()}: results file {written}\n" in out
    )
    assert [p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file()] == [written]
    assert _committed_state() == before
    # a rerun reuses the finished run, says so, and leaves the file (and its provenance) as is
    first = written.read_bytes()
    assert main(["reproduce", "dgb_budget", "--profile", "smoke"]) == 0
    out = capsys.readouterr().out
    assert "reusing the finished DGB run" in out and f"kept {written}" in out
    assert f"reusing what an earlier run of the same config left in {written}" in out
    assert written.read_bytes() == first
    # $SGB_RESULTS moves the default
    monkeypatch.setenv("SGB_RESULTS", str(tmp_path / "elsewhere"))
    assert main(["reproduce", "dgb_budget", "--profile", "smoke"]) == 0
    assert (tmp_path / "elsewhere" / "dgb_budget_digits_smoke.json").is_file()


def test_results_that_come_out_the_same_keep_the_provenance_of_the_run_that_made_them(
    tmp_path,
):
    run = {"config": {"lr": 0.1}, "profile": "cpu", "seeds": [0]}
    path = write_results(tmp_path / "x_cpu.json", {"acc": [0.5]}, run | {"date": "day 1"})
    write_results(path, {"acc": [0.5]}, run | {"date": "day 2", "wall_time_s": 1.0})
    assert json.loads(path.read_text())["provenance"]["date"] == "day 1"
    write_results(path, {"acc": [0.6]}, run | {"date": "day 3"})
    assert json.loads(path.read_text())["provenance"]["date"] == "day 3"
    write_results(path, {"acc": [0.6]}, run | {"seeds": [0, 1], "date": "day 4"})
    assert json.loads(path.read_text())["provenance"]["date"] == "day 4"


def test_help_describes_every_experiment_with_its_figure_inputs_and_costs(capsys):
    with pytest.raises(SystemExit):
        main(["reproduce", "--help"])
    text = capsys.readouterr().out
    assert text.count("\n") > 3 * len(EXPERIMENTS)
    for name, experiment in EXPERIMENTS.items():
        assert experiment.figure and experiment.inputs, f"{name} is not described"
        assert set(experiment.costs) == set(PROFILE_NAMES), f"{name}: cost of every profile"
        assert re.search(rf"^  {name}: ", text, re.MULTILINE)
    flat = " ".join(experiments_help().split())
    datasets = {d for profile in fig2.PROFILES.values() for d in profile}
    assert datasets >= {"fashion-mnist", "digits"}
    for dataset in datasets:
        assert dataset in flat, f"--help does not name fig2's dataset {dataset}"
    assert "--env ant (default) or halfcheetah" in flat
    assert "$SGB_RESULTS" in flat and "./sgb-results" in flat and MAINTAINER_FLAG in flat


def _readme_commands() -> list[str]:
    readme = (ROOT / "README.md").read_text()
    commands = re.findall(r"python -m sgb (reproduce[^`#\n]*)", readme)
    return [c.strip() for c in commands if "--help" not in c]


def test_the_readme_commands_parse_and_match_the_makefile():
    commands = _readme_commands()
    assert len(commands) >= 8
    parser = build_parser()
    for command in commands:
        words = [{"D": "digits", "E": "ant"}.get(w, w) for w in shlex.split(command)]
        parser.parse_args(words)  # exits on an unknown experiment or option
    makefile = (ROOT / "Makefile").read_text()
    assert "$(BIN)/python -m sgb reproduce $(EXPERIMENT) $(ARGS)" in makefile
    readme = (ROOT / "README.md").read_text()
    for experiment, args in re.findall(r'make reproduce EXPERIMENT=(\S+) ARGS="([^"]*)"', readme):
        assert f"reproduce {experiment} {args}" in commands, f"no python line for {args}"


def test_importing_the_package_starts_no_jax_backend_so_the_cli_sets_xla_threads_in_time():
    # ``main`` holds a sweep that shares its runs to one XLA thread before the first run;
    # that takes effect only while no module has started a backend on import
    modules = sorted(
        ".".join(p.relative_to(ROOT).with_suffix("").parts)
        for p in (ROOT / "sgb").rglob("*.py")
        if p.name != "__init__.py"
    )
    code = (
        "import importlib, sys\n"
        "from jax._src import xla_bridge\n"
        f"for name in {modules!r}:\n"
        "    importlib.import_module(name)\n"
        "    if xla_bridge.backends_are_initialized():\n"
        "        sys.exit(f'importing {name} started a JAX backend')\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]


@dataclasses.dataclass(frozen=True)
class _Toy:
    seeds: tuple[int, ...]


def _stand_in_for_bbb(monkeypatch, reads: bool) -> list[str]:
    """bbb's run replaced by a run of seconds of a toy config that reads what an earlier
    run left (``reads``) or does not; the profiles it is run at."""
    profiles = []

    def run(profile: str, out_dir: Path) -> Path:
        profiles.append(profile)
        recording = start({p: _Toy((0, 1)) for p in PROFILE_NAMES}, profile, out_dir, "bbb")
        if reads:
            recording.earlier()
        return recording.write({"value": 1}, seeds=recording.config.seeds)

    monkeypatch.setattr(bayes_by_backprop, "run", run)
    return profiles


@pytest.mark.parametrize("reads", [False, True])
def test_a_rerun_says_it_reuses_an_earlier_results_file_only_where_it_reads_it(
    reads, tmp_path, monkeypatch, capsys
):
    _stand_in_for_bbb(monkeypatch, reads)
    (tmp_path / "other_smoke.json").write_text("{}")  # not of this config: never reused
    assert main(["reproduce", "bbb", "--out-dir", str(tmp_path)]) == 0
    assert "reus" not in capsys.readouterr().out.replace(str(tmp_path), "DIR")
    assert main(["reproduce", "bbb", "--out-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out.replace(str(tmp_path), "DIR")
    reuse = "  reusing what an earlier run of the same config left in DIR/bbb_smoke.json: "
    assert out.count(reuse) == out.count("reus") == reads and "kept DIR/bbb_smoke.json" in out


def test_a_run_says_what_it_is_when_it_starts(tmp_path, monkeypatch, capsys):
    _stand_in_for_bbb(monkeypatch, reads=False)
    assert main(["reproduce", "bbb", "--out-dir", str(tmp_path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[:2] == [
        f"bbb (smoke): results go to {tmp_path}",
        f"bbb, smoke profile, commit {git_commit()}, seeds [0, 1]: results file "
        f"{tmp_path / 'bbb_smoke.json'}",
    ]
    # seeds of a config's parts, and none where the config has none
    parts = {p: {"digits": {"sweep": _Toy((2, 3)), "ablation": None}} for p in PROFILE_NAMES}
    start(parts, "cpu", tmp_path, "toy", choice="digits")
    assert capsys.readouterr().out.endswith(
        f"seeds [2, 3]: results file {tmp_path / 'toy_cpu.json'}\n"
    )
    start({p: None for p in PROFILE_NAMES}, "cpu", tmp_path, "plain")
    assert "seeds" not in capsys.readouterr().out


def test_the_paper_profile_asks_for_a_gpu_or_force_cpu(tmp_path, monkeypatch, capsys):
    profiles = _stand_in_for_bbb(monkeypatch, reads=False)
    monkeypatch.setattr(sgb.__main__, "jax_backend", lambda: "cpu")
    assert main(["reproduce", "bbb", "--profile", "paper", "--out-dir", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert "the paper profile is meant for a GPU" in captured.err and "--force-cpu" in captured.err
    assert captured.out == "" and profiles == [] and list(tmp_path.iterdir()) == []
    paper = ["reproduce", "bbb", "--profile", "paper", "--force-cpu", "--out-dir", str(tmp_path)]
    assert main(paper) == 0
    assert profiles == ["paper"] and (tmp_path / "bbb_paper.json").is_file()
    monkeypatch.setattr(sgb.__main__, "jax_backend", lambda: "gpu")
    assert main(["reproduce", "bbb", "--profile", "paper", "--out-dir", str(tmp_path)]) == 0
    assert profiles == ["paper", "paper"]


def test_the_backend_asked_of_a_child_process_is_jax_s_own():
    assert jax_backend() == jax.default_backend()


def test_help_names_the_default_profile_and_lists_the_experiments_by_chapter(capsys):
    with pytest.raises(SystemExit):
        main(["reproduce", "--help"])
    text = capsys.readouterr().out
    assert "(default: smoke" in " ".join(text.split())
    chapter, found, headings = None, {}, []
    for line in experiments_help().splitlines():
        if heading := re.fullmatch(r"chapter (\d), (.*):", line):
            chapter = int(heading[1])
            headings.append(chapter)
            assert heading[2] == CHAPTERS[chapter]
        elif entry := re.match(r"  (\w+): ", line):
            found[entry[1]] = chapter
    assert headings == sorted({e.chapter for e in EXPERIMENTS.values()})
    assert found == {name: experiment.chapter for name, experiment in EXPERIMENTS.items()}


@pytest.mark.parametrize(
    "args, error",
    [
        (["fig2", "--dataset", "cifar11"], "unknown dataset 'cifar11'; choose one of ['cifar10', "),
        (["fig2", "--dataset", "cifar10"], "'cifar10' has no smoke profile; choose one of "),
        (["fig3", "--env", "walker"], "unknown env 'walker'; choose one of ['ant', 'halfcheetah']"),
    ],
)
def test_a_dataset_or_environment_is_checked_before_anything_runs(args, error, tmp_path, capsys):
    assert main(["reproduce", *args, "--out-dir", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith(f"error: {error}") and captured.out == ""
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("below", ["", "out"])
def test_an_out_dir_a_file_stands_in_for_is_refused_naming_the_file(below, tmp_path, capsys):
    taken = tmp_path / "taken"
    taken.write_text("")
    assert main(["reproduce", "bbb", "--out-dir", str(taken / below)]) == 2
    captured = capsys.readouterr()
    assert captured.err == (
        f"error: cannot write results under {taken / below}: {taken} is a file, not a directory\n"
    )
    assert captured.out == "" and taken.read_text() == ""
