"""Recording a run: the one way every experiment checks its profile, names its results
file, continues what an earlier run of the same config left there, times itself and
writes its results with provenance, atomically (``sgb.provenance``).

    recording = start(PROFILES, profile, out_dir, "bbb")
    results = compute(recording.config)
    return recording.write(results, seeds=recording.config.seeds)

An experiment made of parts (cells, chunks, runs, each a record with its own
``wall_time_s`` and ``git_commit``) passes them to ``write``: the file's wall time is then
their sum, whenever each part ran, and ``git_commits`` lists the commits that made them.
"""

import dataclasses
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, Generic, TypeVar

from sgb.experiments import check_profile
from sgb.provenance import earlier_results, provenance, results_file, write_results

Config = TypeVar("Config")


@dataclasses.dataclass(frozen=True)
class Recording(Generic[Config]):
    """One run of an experiment at ``profile``: its config, its results file and when it
    began (``time.perf_counter()``, s)."""

    config: Config
    profile: str
    path: Path
    began: float

    def earlier(self) -> dict[str, Any]:
        """The results an earlier run of this config left in the file (``{}`` if none); a
        ValueError if a run of another config wrote it."""
        return earlier_results(self.path, self.config)

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
    any work."""
    config = profiles[check_profile(profile)]
    if choice is not None:
        if choice not in config:
            raise ValueError(f"{choice!r} has no {profile} profile; choose one of {sorted(config)}")
        config = config[choice]
    name = stem(config) if callable(stem) else stem
    return Recording(config, profile, results_file(out_dir, name, profile), time.perf_counter())
