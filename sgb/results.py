"""The committed results as data: a file's payload, the files read by experiment
(``Records``), a file's provenance in one line. Each experiment's tables of its results
lie in its module.

``name`` is a results file's path under ``results_dir`` (default
``sgb.paths.committed_results()``), e.g. ``"rl/fig3_ant_cpu.json"``.

``load`` is the one door: it refuses (``sgb.validation.CorruptFile``, naming the file) a
file that is not a results file, that is not as its run wrote it (``sgb.provenance``'s
checksum, ``sgb.manifest``), or that does not parse under its schema (``sgb.schemas``).
"""

from pathlib import Path
from typing import NamedTuple

from sgb import manifest, schemas
from sgb.paths import committed_results
from sgb.provenance import read_results, verify_checksum
from sgb.schemas import ResultsFile


def path(name: str, results_dir: str | Path | None = None) -> Path:
    """Where the results file ``name`` lies under ``results_dir``."""
    return Path(committed_results() if results_dir is None else results_dir) / name


def load(
    name: str,
    model: type[ResultsFile],
    results_dir: str | Path | None = None,
    missing_ok: bool = False,
) -> ResultsFile | None:
    """Results file ``name`` as a record of ``model``, once it is checked: strict JSON,
    matching the checksum its run embedded (``sgb.provenance.verify_checksum``), its entry
    in the manifest of ``results_dir`` (``sgb.manifest.verify``) and its model
    (``sgb.schemas.check``), else a ``CorruptFile`` naming it. ``None`` if it is absent
    and ``missing_ok``, else ``FileNotFoundError`` naming it."""
    root = Path(committed_results() if results_dir is None else results_dir)
    file = root / name
    if not file.exists():
        if missing_ok:
            return None
        raise FileNotFoundError(f"no results file {file}: run `python -m sgb reproduce` for it")
    payload = read_results(file, schemas.REWRITE)
    verify_checksum(file, payload, schemas.REWRITE)
    manifest.verify(file, root)
    return schemas.check(model, payload, file)


class Source(NamedTuple):
    """An experiment's results: part ("" for one file, else a body) -> file name, and the
    model of its files."""

    files: dict[str, str]
    model: type[ResultsFile]


class Records:
    """The results files of ``results_dir`` (default: the committed ones), each named by
    its experiment (a key of ``sources``: the registry's ``sgb.experiments.EXPERIMENTS``
    and the benchmarks) and part (a body, or ``""`` for an experiment of one file), read
    once each through ``load`` as records of their model.

        records("fig3", "ant")        # the record, or FileNotFoundError naming the file
        records.get("regime_peer")    # the record, or None where it was never run
    """

    def __init__(self, sources: dict[str, Source], results_dir: str | Path | None = None) -> None:
        self.sources = sources
        self.results_dir = Path(committed_results() if results_dir is None else results_dir)
        self._read: dict[str, ResultsFile | None] = {}

    def name(self, experiment: str, part: str = "") -> str:
        """The file name of ``experiment``'s ``part``."""
        files = self.sources[experiment].files if experiment in self.sources else {}
        if part not in files:
            raise ValueError(
                f"experiment {experiment!r} declares no results file {part!r}: {sorted(files)}"
            )
        return files[part]

    def get(self, experiment: str, part: str = "") -> ResultsFile | None:
        """The record of ``experiment``'s ``part``, or None if its file is absent."""
        name = self.name(experiment, part)
        if name not in self._read:
            model = self.sources[experiment].model
            self._read[name] = load(name, model, self.results_dir, missing_ok=True)
        return self._read[name]

    def __call__(self, experiment: str, part: str = "") -> ResultsFile:
        """The record of ``experiment``'s ``part``; FileNotFoundError if it is absent."""
        record = self.get(experiment, part)
        if record is None:
            file = self.results_dir / self.name(experiment, part)
            raise FileNotFoundError(
                f"no results file {file}: run `python -m sgb reproduce {experiment}` for it"
            )
        return record


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 2 * 3600:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def provenance_line(record: ResultsFile) -> str:
    """One line of where a results file comes from: profile, seeds, the commits that ran
    it (10 hex digits each, ``+dirty`` kept), date and wall time on its backend."""
    made = record.provenance
    shown = (c[:10] + c[40:] for c in made.git_commits or [made.git_commit])
    commits = ", ".join(dict.fromkeys(shown))  # in order, each once
    return (
        f"profile {made.profile}, seeds {made.seeds}, commit {commits}, "
        f"{made.date[:10]}, {_duration(made.wall_time_s)} on {made.backend}"
    )
