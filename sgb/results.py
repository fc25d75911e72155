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
from typing import Any

from sgb import manifest, schemas
from sgb.paths import committed_results
from sgb.provenance import read_results, verify_checksum

Payload = dict[str, Any]  # a results file: {"results": ..., "provenance": ...}


def path(name: str, results_dir: str | Path | None = None) -> Path:
    """Where the results file ``name`` lies under ``results_dir``."""
    return Path(committed_results() if results_dir is None else results_dir) / name


def load(
    name: str, results_dir: str | Path | None = None, missing_ok: bool = False
) -> Payload | None:
    """The payload of results file ``name``, once it is checked: strict JSON, matching the
    checksum its run embedded (``sgb.provenance.verify_checksum``), its entry in the
    manifest of ``results_dir`` (``sgb.manifest.verify``) and its schema
    (``sgb.schemas.check``), else a ``CorruptFile`` naming it. ``None`` if it is absent and
    ``missing_ok``, else ``FileNotFoundError`` naming it."""
    root = Path(committed_results() if results_dir is None else results_dir)
    file = root / name
    if not file.exists():
        if missing_ok:
            return None
        raise FileNotFoundError(f"no results file {file}: run `python -m sgb reproduce` for it")
    payload = read_results(file, schemas.REWRITE)
    verify_checksum(file, payload, schemas.REWRITE)
    manifest.verify(file, root)
    schemas.check(name, payload, file)
    return payload


class Records:
    """The results files of ``results_dir`` (default: the committed ones), each named by
    its experiment (a key of the registry ``sgb.experiments.EXPERIMENTS``) and part (a
    body, a dataset, or ``""`` for an experiment of one file), read once each through
    ``load``. ``files`` maps experiment -> part -> file name, as the registry declares them.

        records("fig3", "ant")        # the payload, or FileNotFoundError naming the file
        records.get("regime_peer")    # the payload, or None where it was never run
    """

    def __init__(
        self, files: dict[str, dict[str, str]], results_dir: str | Path | None = None
    ) -> None:
        self.files = files
        self.results_dir = Path(committed_results() if results_dir is None else results_dir)
        self._read: dict[str, Payload | None] = {}

    def name(self, experiment: str, part: str = "") -> str:
        """The file name of ``experiment``'s ``part``."""
        parts = self.files.get(experiment, {})
        if part not in parts:
            raise ValueError(
                f"experiment {experiment!r} declares no results file {part!r}: {sorted(parts)}"
            )
        return parts[part]

    def get(self, experiment: str, part: str = "") -> Payload | None:
        """The payload of ``experiment``'s ``part``, or None if it is absent."""
        name = self.name(experiment, part)
        if name not in self._read:
            self._read[name] = load(name, self.results_dir, missing_ok=True)
        return self._read[name]

    def __call__(self, experiment: str, part: str = "") -> Payload:
        """The payload of ``experiment``'s ``part``; FileNotFoundError if it is absent."""
        payload = self.get(experiment, part)
        if payload is None:
            file = self.results_dir / self.name(experiment, part)
            raise FileNotFoundError(
                f"no results file {file}: run `python -m sgb reproduce {experiment}` for it"
            )
        return payload


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 2 * 3600:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def provenance_line(payload: Payload) -> str:
    """One line of where a results file comes from: profile, seeds, the commits that ran
    it (10 hex digits each, ``+dirty`` kept), date and wall time on its backend."""
    record = payload["provenance"]
    shown = (c[:10] + c[40:] for c in record.get("git_commits", [record["git_commit"]]))
    commits = ", ".join(dict.fromkeys(shown))  # in order, each once
    return (
        f"profile {record['profile']}, seeds {record['seeds']}, commit {commits}, "
        f"{record['date'][:10]}, {_duration(record['wall_time_s'])} on {record['backend']}"
    )
