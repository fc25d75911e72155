"""Recording a run: the one way every experiment checks its profile, names its results
file, says what it is when it starts, continues what an earlier run of the same config
left there, times itself and writes its results with provenance, atomically
(``sgb.provenance``).

    recording = start(PROFILES, profile, out_dir, "bbb")
    results = compute(recording.config)
    return recording.write(results, seeds=recording.config.seeds)

An experiment made of parts (cells, chunks, runs, each a record with its own
``wall_time_s`` and ``git_commit``) passes them to ``write``: the file's wall time is then
their sum, whenever each part ran, and ``git_commits`` lists the commits that made them.
"""

import contextlib
import dataclasses
import json
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, Generic, TypeVar

from sgb import manifest
from sgb.profiles import check_profile
from sgb.provenance import (
    CHECKSUM,
    SAME_RUN_FIELDS,
    atomic_write,
    git_commit,
    jsonable,
    payload_digest,
    provenance,
    read_results,
    results_file,
)
from sgb.validation import RESTART, CorruptFile


def write_results(path: str | Path, results: dict[str, Any], record: dict[str, Any]) -> Path:
    """Write ``{"provenance": record, "results": results}`` as strict JSON (non-finite
    numbers as ``null``), atomically, with the payload's ``payload_digest`` in its
    provenance (``CHECKSUM``); returns the path. A file written into the committed results
    is entered into their manifest (``sgb.manifest.record``).

    A file that already holds these results, of the same config, profile and seeds, is
    left as it is: a rerun that reused finished runs, or came out the same, does not
    replace the provenance of the run that made them (its commit, date and wall time)."""
    payload = {"provenance": jsonable(record), "results": jsonable(results)}
    payload["provenance"][CHECKSUM] = payload_digest(payload)
    text = json.dumps(payload, indent=1, sort_keys=False, allow_nan=False) + "\n"
    if not _holds_the_same(path, json.loads(text)):
        atomic_write(path, text.encode())
    manifest.record(path)
    return Path(path)


def _holds_the_same(path: str | Path, payload: dict[str, Any]) -> bool:
    try:
        old = read_results(path)
    except (OSError, ValueError):
        return False
    if not isinstance(old, dict) or old.get("results") != payload["results"]:
        return False
    before, now = old.get("provenance") or {}, payload["provenance"]
    return all(before.get(key) == now.get(key) for key in SAME_RUN_FIELDS)


_superseding = False  # set by ``superseding``


@contextlib.contextmanager
def superseding() -> Iterator[None]:
    """Within it, a run whose results file holds the results of another config deletes
    that file and starts afresh, where it would otherwise refuse: the background queue's
    workers run so (``sgb.grid.work``), in a worktree where git keeps the committed file,
    so that a run of a new design replaces the file of the old one when it lands."""
    global _superseding
    before, _superseding = _superseding, True
    try:
        yield
    finally:
        _superseding = before


def earlier_results(path: str | Path, config: Any) -> dict[str, Any]:
    """The results an earlier run of ``config`` left in ``path`` (empty if there is no file),
    so that a rerun continues it; a ValueError if a run of another config wrote the file
    (outside ``superseding``), a ``sgb.validation.CorruptFile`` if it is not a results file
    with a config or, in the committed results, not the file its run wrote
    (``sgb.manifest.verify``)."""
    results = _results_of(path, config)
    if results is not None:
        return results
    if not _superseding:
        raise ValueError(f"{path} holds results of another config; move it away to run this one")
    print(f"{path} holds results of another config: deleted, this run starts afresh", flush=True)
    Path(path).unlink(missing_ok=True)  # another worker may have deleted it first
    return {}


def held_results(path: str | Path, config: Any) -> dict[str, Any]:
    """``earlier_results``, but ``{}`` where a run of another config wrote ``path``: for a
    listing of the runs still to do (``queued``), which a file of an earlier design must
    not stop."""
    results = _results_of(path, config)
    return {} if results is None else results


def _results_of(path: str | Path, config: Any) -> dict[str, Any] | None:
    """The results in ``path`` of a run of ``config`` (``{}`` without the file, ``None``
    where a run of another config wrote it); a CorruptFile as ``earlier_results`` says."""
    try:
        payload = read_results(path)
        manifest.verify(path)
    except FileNotFoundError:  # none, or another worker's ``superseding`` deleted it
        return {}
    for part in ("provenance", "results"):
        if not isinstance(payload, dict) or not isinstance(payload.get(part), dict):
            problem = f'has no "{part}" object, so is not a results file'
            raise CorruptFile(path, problem, RESTART, "results file")
    if "config" not in payload["provenance"]:
        raise CorruptFile(path, "has no config in its provenance", RESTART, "results file")
    if payload["provenance"]["config"] != json.loads(json.dumps(jsonable(config))):
        return None
    return payload["results"]


Config = TypeVar("Config")


@dataclasses.dataclass
class Recording(Generic[Config]):
    """One run of an experiment at ``profile``: its config, its results file and when it
    began (``time.perf_counter()``, s)."""

    config: Config
    profile: str
    path: Path
    began: float
    _read: bool = dataclasses.field(default=False, init=False, repr=False, compare=False)

    def earlier(self) -> dict[str, Any]:
        """The results an earlier run of this config left in the file (``{}`` if none); a
        ValueError if a run of another config wrote it. The first read says when it finds
        some, which the run then reuses (later reads may find this run's own)."""
        results = earlier_results(self.path, self.config)
        if results and not self._read:
            print(
                f"  reusing what an earlier run of the same config left in {self.path}: "
                "its finished parts are not redone",
                flush=True,
            )
        self._read = True
        return results

    def write(
        self,
        results: dict[str, Any],
        seeds: Iterable[int],
        parts: Sequence[Mapping[str, Any]] | None = None,
    ) -> Path:
        """Write ``results`` with provenance, atomically; returns the path. The wall time is
        the sum of the ``parts``' own when they are given, else the time since ``began``."""
        if parts is None:
            wall = time.perf_counter() - self.began
        else:
            wall = sum(part["wall_time_s"] for part in parts)
        record = provenance(self.config, self.profile, list(seeds), wall)
        if parts is not None:
            record["git_commits"] = sorted({part["git_commit"] for part in parts})
        return write_results(self.path, results, record)


def start(
    profiles: Mapping[str, Any],
    profile: str,
    out_dir: str | Path,
    stem: str | Callable[[Any], str],
    choice: str | None = None,
) -> Recording:
    """Begin a run at ``profile`` of the experiment whose configs are ``profiles``
    (profile -> config; with ``choice``, profile -> {dataset or environment -> config}).

    Its results file is ``out_dir/{stem}_{profile}.json`` (``stem`` may be a function of
    the config); a bad profile or choice, or an unwritable ``out_dir``, fails here, before
    any work. It says what runs: the stem, the profile, the commit, the config's seeds
    (where it has them) and the results file."""
    config = pick(profiles, profile, choice)
    name = stem(config) if callable(stem) else stem
    path = results_file(out_dir, name, profile)
    seeds = _seeds(config)
    print(
        f"{name}, {profile} profile, commit {git_commit()}"
        f"{f', seeds {seeds}' if seeds else ''}: results file {path}",
        flush=True,
    )
    return Recording(config, profile, path, time.perf_counter())


def pick(profiles: Mapping[str, Any], profile: str, choice: str | None = None) -> Any:
    """The config of ``profile`` in ``profiles`` (with ``choice``, its config for that
    dataset or environment); a ValueError for a profile or choice they do not hold."""
    config = profiles[check_profile(profile)]
    if choice is None:
        return config
    if choice not in config:
        raise ValueError(f"{choice!r} has no {profile} profile; choose one of {sorted(config)}")
    return config[choice]


def _seeds(config: Any) -> list[int]:
    """The seeds ``config`` names: its ``seeds``, else its ``seed``, else those of its
    parts where it is a mapping (``[]`` if none)."""
    if isinstance(config, Mapping):
        return sorted({seed for part in config.values() for seed in _seeds(part)})
    if hasattr(config, "seeds"):
        return list(config.seeds)
    return [config.seed] if hasattr(config, "seed") else []
