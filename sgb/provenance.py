"""Provenance of results: config, profile, seeds, git commit, versions, date, wall time."""

import dataclasses
import datetime
import functools
import hashlib
import importlib.metadata
import json
import math
import os
import platform
import subprocess
import tempfile
from pathlib import Path
from typing import Any

TRACKED_PACKAGES = ("jax", "jaxlib", "flax", "optax", "brax", "mujoco", "numpy")


def package_versions() -> dict[str, str]:
    """Installed versions of python, sgb and the packages results depend on."""
    from sgb import __version__

    versions = {"python": platform.python_version(), "sgb": __version__}
    for name in TRACKED_PACKAGES:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions


@functools.cache
def git_commit() -> str:
    """The commit of the working tree when this process first asked, or "unknown": the
    code the process runs, whatever is committed while it runs.

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


NULL_MEANS = "null stands for a value that is not a finite number (e.g. an SEM of one seed)"


def jsonable(value: Any) -> Any:
    """``value`` as strict JSON data: nan and inf become ``None`` (``null``)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {"type": type(value).__name__, **jsonable(dataclasses.asdict(value))}
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if hasattr(value, "tolist"):
        return jsonable(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def results_file(out_dir: str | Path, stem: str, profile: str) -> Path:
    """``out_dir/{stem}_{profile}.json``, the one naming of results files, so that no profile
    ever writes over another's. Checks that ``out_dir`` is (or can be made) a writable
    directory, so a bad location fails before an experiment starts, not after it."""
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out_dir):
            pass
    except OSError as error:
        raise ValueError(f"cannot write results under {out_dir}: {error}") from error
    return out_dir / f"{stem}_{profile}.json"


def atomic_write(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same directory and
    ``os.replace``: a failed write leaves the old file untouched."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def provenance(config: Any, profile: str, seeds: list[int], wall_time_s: float) -> dict[str, Any]:
    """The provenance record every results file carries."""
    import jax

    return {
        "config": jsonable(config),
        "profile": profile,
        "seeds": list(seeds),
        "git_commit": git_commit(),
        "versions": package_versions(),
        "backend": jax.default_backend(),
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "wall_time_s": round(float(wall_time_s), 2),
        "null": NULL_MEANS,
    }


# What makes two results files the same: their results and these fields of their provenance
# (the others say when, where and how fast a run made them).
SAME_RUN_FIELDS = ("config", "profile", "seeds")


CHECKSUM = "payload_sha256"


def payload_digest(payload: dict[str, Any]) -> str:
    """The sha256 (hex) of ``payload`` as canonical JSON (sorted keys, no spaces), leaving
    out its provenance's own ``CHECKSUM``: what a run writes into the provenance of its
    results file, and what a reader recomputes from the file's parsed contents."""
    record = {k: v for k, v in payload["provenance"].items() if k != CHECKSUM}
    canonical = {"provenance": record, "results": payload.get("results")}
    text = json.dumps(canonical, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def _finite(text: str) -> float:
    """A JSON number as a float; NaN, Infinity and numbers beyond a float's range (such as
    1e999) are not strict JSON, and no run writes them."""
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text} is not a finite number")
    return value


def read_results(path: str | Path, remedy: str | None = None) -> Any:
    """Read a results file written by ``write_results``; a directory or a file that is not
    strict JSON raises ``sgb.validation.CorruptFile`` naming it, with ``remedy`` (default:
    run afresh). Its shape and checksum are checked by the readers that rely on them
    (``sgb.results.load``, ``earlier_results``)."""
    from sgb.validation import RESTART, CorruptFile

    def corrupt(problem: str) -> CorruptFile:
        return CorruptFile(path, problem, remedy or RESTART, "results file")

    try:
        return json.loads(Path(path).read_bytes(), parse_float=_finite, parse_constant=_finite)
    except IsADirectoryError as error:
        raise corrupt("is a directory, not a results file") from error
    except (UnicodeDecodeError, ValueError) as error:
        raise corrupt(f"is not a results file ({error})") from error


def verify_checksum(path: str | Path, payload: Any, remedy: str) -> None:
    """Refuse ``payload``, read from results file ``path``, if its provenance carries a
    ``CHECKSUM`` that its contents no longer match (an edit after its run wrote it): a
    ``sgb.validation.CorruptFile`` naming the file, with ``remedy``. A file written before
    runs embedded the checksum carries none."""
    from sgb.validation import CorruptFile

    record = payload.get("provenance") if isinstance(payload, dict) else None
    written = record.get(CHECKSUM) if isinstance(record, dict) else None
    if written is not None and written != payload_digest(payload):
        problem = f"is not as its run wrote it: its contents do not match its {CHECKSUM}"
        raise CorruptFile(path, problem, remedy, "results file")
