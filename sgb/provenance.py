"""Provenance of results: config, profile, seeds, git commit, versions, date, wall time."""

import dataclasses
import datetime
import importlib.metadata
import json
import platform
import subprocess
from pathlib import Path
from typing import Any

TRACKED_PACKAGES = ("sgb", "jax", "jaxlib", "flax", "optax", "brax", "mujoco", "numpy")


def package_versions() -> dict[str, str]:
    """Installed versions of python and the packages results depend on."""
    versions = {"python": platform.python_version()}
    for name in TRACKED_PACKAGES:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


def git_commit() -> str:
    """The commit of the working tree, or "unknown".

    ``+dirty`` marks changes to tracked files outside ``results/`` (results files written
    by an earlier experiment of the same run do not count).
    """
    root = Path(__file__).resolve().parent.parent
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=root, capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", ".", ":!results"],
            cwd=root,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return commit + ("+dirty" if dirty else "")


def _jsonable(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {"type": type(value).__name__, **_jsonable(dataclasses.asdict(value))}
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if hasattr(value, "tolist"):
        return value.tolist()
    return value


def provenance(config: Any, profile: str, seeds: list[int], wall_time_s: float) -> dict[str, Any]:
    """The provenance record every results file carries."""
    import jax

    return {
        "config": _jsonable(config),
        "profile": profile,
        "seeds": list(seeds),
        "git_commit": git_commit(),
        "versions": package_versions(),
        "backend": jax.default_backend(),
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "wall_time_s": round(float(wall_time_s), 2),
    }


def write_results(path: str | Path, results: dict[str, Any], record: dict[str, Any]) -> Path:
    """Write ``{"provenance": record, "results": results}`` as JSON; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = {"provenance": record, "results": _jsonable(results)}
    path.write_text(json.dumps(payload, indent=1, sort_keys=False) + "\n")
    return path


def read_results(path: str | Path) -> dict[str, Any]:
    """Read a results file written by ``write_results``."""
    return json.loads(Path(path).read_text())
